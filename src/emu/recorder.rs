//! Ground-truth recording, out of band: one CSV row per physics step,
//! `t_s,cmd_0..cmd_{N-1},pos_0..pos_{N-1},torque_0..torque_{N-1}`.
//! `cmd_i` is the position set-point module `i` applied during the step (`NaN` when
//! limp or not position-commanded); `pos_i` and `torque_i` are the plant's exact
//! (noise-free) joint angle, rad, and spring torque, N·m, at the end of the step.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use super::Plant;
use crate::protocol::Command;

/// Rows between flushes.
pub const FLUSH_EVERY_ROWS: u32 = 1000;

#[derive(Debug, thiserror::Error)]
#[error("recording {path}: {source}")]
pub struct RecordError {
    pub path: PathBuf,
    #[source]
    pub source: io::Error,
}

/// Buffered CSV writer of the ground truth.
pub struct Recorder {
    path: PathBuf,
    out: BufWriter<File>,
    modules: usize,
    rows_since_flush: u32,
}

impl Recorder {
    /// Create (truncate) `path` and write the header for `modules` joints.
    pub fn create(path: &Path, modules: usize) -> Result<Self, RecordError> {
        let wrap = |source| RecordError {
            path: path.to_owned(),
            source,
        };
        let file = File::create(path).map_err(wrap)?;
        let mut r = Self {
            path: path.to_owned(),
            out: BufWriter::with_capacity(1 << 16, file),
            modules,
            rows_since_flush: 0,
        };
        r.header().map_err(wrap)?;
        Ok(r)
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    fn header(&mut self) -> io::Result<()> {
        write!(self.out, "t_s")?;
        for kind in ["cmd", "pos", "torque"] {
            for i in 0..self.modules {
                write!(self.out, ",{kind}_{i}")?;
            }
        }
        writeln!(self.out)
    }

    /// Append the row of one physics step.
    pub fn row(&mut self, plant: &dyn Plant, applied: &[Command]) -> Result<(), RecordError> {
        self.write_row(plant, applied)
            .map_err(|source| RecordError {
                path: self.path.clone(),
                source,
            })
    }

    fn write_row(&mut self, plant: &dyn Plant, applied: &[Command]) -> io::Result<()> {
        write!(self.out, "{:.6}", plant.time_s())?;
        for i in 0..self.modules {
            let c = applied.get(i).copied().unwrap_or(Command::LIMP);
            write!(self.out, ",{}", c.position_rad)?;
        }
        for i in 0..self.modules {
            write!(self.out, ",{:.6}", plant.ground_truth(i).position_rad)?;
        }
        for i in 0..self.modules {
            write!(self.out, ",{:.5}", plant.ground_truth(i).torque_nm)?;
        }
        writeln!(self.out)?;
        self.rows_since_flush += 1;
        if self.rows_since_flush >= FLUSH_EVERY_ROWS {
            self.rows_since_flush = 0;
            self.out.flush()?;
        }
        Ok(())
    }

    /// Flush everything written so far.
    pub fn flush(&mut self) -> Result<(), RecordError> {
        self.rows_since_flush = 0;
        self.out.flush().map_err(|source| RecordError {
            path: self.path.clone(),
            source,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emu::plant::{JointSpacePlant, NoiseConfig, PlantConfig};

    #[test]
    fn writes_header_and_rows() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("gt.csv");
        let mut plant = JointSpacePlant::new(PlantConfig {
            noise: NoiseConfig::NONE,
            ..PlantConfig::new(2)
        })
        .unwrap();
        let mut rec = Recorder::create(&path, 2).unwrap();
        let cmds = [Command::position(0.5), Command::LIMP];
        for _ in 0..3 {
            plant.step(1e-3, &cmds);
            rec.row(&plant, &cmds).unwrap();
        }
        rec.flush().unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "t_s,cmd_0,cmd_1,pos_0,pos_1,torque_0,torque_1");
        assert_eq!(lines.len(), 4);
        let last: Vec<&str> = lines[3].split(',').collect();
        assert_eq!(last.len(), 7);
        assert_eq!(last[0], "0.003000");
        assert_eq!(last[1], "0.5");
        assert_eq!(last[2], "NaN");
        assert!(last[3].parse::<f64>().unwrap() > 0.0);
    }
}
