//! Ground truth of the bodies, out of band (the daemon never sees it): one CSV row per
//! physics step, `t_s, x_k,y_k,z_k,qw_k,qx_k,qy_k,qz_k for every link k, contacts,
//! normal_force_n`. Positions in m (world frame, z up), orientation as a unit
//! quaternion; `contacts` is the number of link–obstacle collider pairs touching and
//! `normal_force_n` the sum of their normal forces, N. For the physics plant link 0 is
//! the head and link `i + 1` module `i`'s output side.

use std::path::Path;

use super::Plant;
use super::truth_csv::{CsvError, CsvSink};

/// Buffered CSV writer of body poses and contacts.
pub struct PoseCsv {
    sink: CsvSink,
    links: usize,
}

impl PoseCsv {
    /// Create (truncate) `path` and write the header for `links` bodies.
    pub fn create(path: &Path, links: usize) -> Result<Self, CsvError> {
        let sink = CsvSink::create(path, |out| {
            write!(out, "t_s")?;
            for k in 0..links {
                for f in ["x", "y", "z", "qw", "qx", "qy", "qz"] {
                    write!(out, ",{f}_{k}")?;
                }
            }
            writeln!(out, ",contacts,normal_force_n")
        })?;
        Ok(Self { sink, links })
    }

    /// Append the row of one physics step.
    pub fn row(&mut self, plant: &dyn Plant) -> Result<(), CsvError> {
        let links = self.links;
        self.sink.row(|out| {
            write!(out, "{:.6}", plant.time_s())?;
            for k in 0..links {
                let p = plant.link_pose(k);
                for x in p.position_m {
                    write!(out, ",{x:.6}")?;
                }
                for q in p.quat_wxyz {
                    write!(out, ",{q:.6}")?;
                }
            }
            let c = plant.contacts();
            writeln!(out, ",{},{:.3}", c.pairs, c.normal_force_n)
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
    use crate::emu::world::WorldSpec;
    use crate::emu::world::physics::{PhysicsConfig, PhysicsPlant};
    use crate::module::Command;

    #[test]
    fn writes_poses_and_contacts() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("poses.csv");
        let mut plant = PhysicsPlant::new(
            &WorldSpec::default(),
            PhysicsConfig {
                modules: 2,
                ..PhysicsConfig::default()
            },
        )
        .unwrap();
        let mut rec = PoseCsv::create(&path, plant.link_count()).unwrap();
        for _ in 0..3 {
            plant.step(1e-3, &[Command::position(0.0); 2]);
            rec.row(&plant).unwrap();
        }
        rec.flush().unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 4);
        assert!(lines[0].starts_with("t_s,x_0,y_0,z_0,qw_0,qx_0,qy_0,qz_0,x_1"));
        assert!(lines[0].ends_with(",qz_2,contacts,normal_force_n"));
        let last: Vec<&str> = lines[3].split(',').collect();
        assert_eq!(last.len(), 1 + 3 * 7 + 2);
        // Resting on the ground: every link touches it, z about the module radius.
        assert_eq!(last[22], "3");
        let z0: f64 = last[3].parse().unwrap();
        assert!((z0 - 0.0255).abs() < 0.005, "{z0}");
    }
}
