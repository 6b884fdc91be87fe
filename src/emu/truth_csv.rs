//! Ground-truth recording, out of band: one CSV row per physics step,
//! `t_s,cmd_0..cmd_{N-1},pos_0..pos_{N-1},torque_0..torque_{N-1}`.
//! `cmd_i` is the position set-point module `i` applied during the step (`NaN` when
//! limp or not position-commanded); `pos_i` and `torque_i` are the plant's exact
//! (noise-free) joint angle, rad, and spring torque, N·m, at the end of the step.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use super::Plant;
use crate::module::Command;

/// Rows between flushes.
pub const FLUSH_EVERY_ROWS: u32 = 1000;

#[derive(Debug, thiserror::Error)]
#[error("recording {path}: {source}")]
pub struct CsvError {
    pub path: PathBuf,
    #[source]
    pub source: io::Error,
}

/// A buffered CSV file flushed every [`FLUSH_EVERY_ROWS`] rows and on request, whose
/// I/O errors name the file. [`TruthCsv`] and `pose_csv::PoseCsv` write their own columns into it.
pub struct CsvSink {
    path: PathBuf,
    out: BufWriter<File>,
    rows_since_flush: u32,
}

impl CsvSink {
    /// Create (truncate) `path` and write its header line with `header`.
    pub fn create(
        path: &Path,
        header: impl FnOnce(&mut dyn Write) -> io::Result<()>,
    ) -> Result<Self, CsvError> {
        let wrap = |source| CsvError {
            path: path.to_owned(),
            source,
        };
        let file = File::create(path).map_err(wrap)?;
        let mut out = BufWriter::with_capacity(1 << 16, file);
        header(&mut out).map_err(wrap)?;
        Ok(Self {
            path: path.to_owned(),
            out,
            rows_since_flush: 0,
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Append one row written by `fill` (which ends it with a newline).
    pub fn row(
        &mut self,
        fill: impl FnOnce(&mut dyn Write) -> io::Result<()>,
    ) -> Result<(), CsvError> {
        let written = fill(&mut self.out).and_then(|()| {
            self.rows_since_flush += 1;
            if self.rows_since_flush >= FLUSH_EVERY_ROWS {
                self.rows_since_flush = 0;
                self.out.flush()?;
            }
            Ok(())
        });
        written.map_err(|source| self.error(source))
    }

    /// Flush everything written so far.
    pub fn flush(&mut self) -> Result<(), CsvError> {
        self.rows_since_flush = 0;
        self.out.flush().map_err(|source| self.error(source))
    }

    fn error(&self, source: io::Error) -> CsvError {
        CsvError {
            path: self.path.clone(),
            source,
        }
    }
}

/// Buffered CSV writer of the ground truth.
pub struct TruthCsv {
    sink: CsvSink,
    modules: usize,
}

impl TruthCsv {
    /// Create (truncate) `path` and write the header for `modules` joints.
    pub fn create(path: &Path, modules: usize) -> Result<Self, CsvError> {
        let sink = CsvSink::create(path, |out| {
            write!(out, "t_s")?;
            for kind in ["cmd", "pos", "torque"] {
                for i in 0..modules {
                    write!(out, ",{kind}_{i}")?;
                }
            }
            writeln!(out)
        })?;
        Ok(Self { sink, modules })
    }

    pub fn path(&self) -> &Path {
        self.sink.path()
    }

    /// Append the row of one physics step.
    pub fn row(&mut self, plant: &dyn Plant, applied: &[Command]) -> Result<(), CsvError> {
        let modules = self.modules;
        self.sink.row(|out| {
            write!(out, "{:.6}", plant.time_s())?;
            for i in 0..modules {
                let c = applied.get(i).copied().unwrap_or(Command::LIMP);
                write!(out, ",{}", c.position_rad)?;
            }
            for i in 0..modules {
                write!(out, ",{:.6}", plant.ground_truth(i).position_rad)?;
            }
            for i in 0..modules {
                write!(out, ",{:.5}", plant.ground_truth(i).torque_nm)?;
            }
            writeln!(out)
        })
    }

    /// Flush everything written so far.
    pub fn flush(&mut self) -> Result<(), CsvError> {
        self.sink.flush()
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
        let mut rec = TruthCsv::create(&path, 2).unwrap();
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
