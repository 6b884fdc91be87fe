//! `[bus]` (which network the loop drives) and `[hebi]` (modules through HEBI's
//! libhebi: docs/hebi.md). `[network]`'s feedback rate and command lifetime apply to
//! every bus.
use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::config::{Config, ConfigFileError};
use crate::bus::hebi::gains::{self, GainSet};
use crate::num::Num;

#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BusChoice {
    /// Modules speaking protocol v2 over UDP (`[network]`; snake-emu).
    #[default]
    Udp,
    /// Modules through HEBI's C library (`[hebi]`).
    Hebi,
}

#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BusSection {
    pub kind: BusChoice,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HebiConfig {
    /// libhebi.so.2.x; empty = $SNAKED_LIBHEBI, an installed hebi-py, target/hebi/.
    pub library: PathBuf,
    /// Addresses the lookup sends to (e.g. ["10.10.1.255"]); empty = libhebi's default,
    /// a broadcast on every interface but loopback.
    pub interfaces: Vec<String>,
    pub family: String,
    /// Module names head first; empty = `modules` of the family in the lookup's order.
    pub names: Vec<String>,
    /// With `names` empty: how many modules of the family make the group.
    pub modules: usize,
    /// Body position i is the group's module order[i]; empty = the group's order.
    pub order: Vec<usize>,
    /// More than 0: HEBI's imitation group of this many modules, no lookup (tests).
    pub imitation: usize,
    pub lookup_timeout_s: f64,
    pub gains: HebiGains,
}

/// Gains and control strategy by role (`bus::hebi::gains`).
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HebiGains {
    pub all: GainSet,
    pub lateral: GainSet,
    pub dorsal: GainSet,
}

impl Default for HebiConfig {
    fn default() -> Self {
        Self {
            library: PathBuf::new(),
            interfaces: vec![],
            family: "SEA".into(),
            names: vec![],
            modules: 18,
            order: vec![],
            imitation: 0,
            lookup_timeout_s: 2.0,
            gains: HebiGains::default(),
        }
    }
}

impl HebiConfig {
    /// How many modules the group has.
    pub fn module_count(&self) -> usize {
        if self.imitation > 0 {
            self.imitation
        } else if !self.names.is_empty() {
            self.names.len()
        } else {
            self.modules
        }
    }
}

impl Config {
    /// `[bus]` and `[hebi]`: what would stop a HEBI bus later (the library included).
    pub(super) fn bus_checks(&self, path: &Path) -> Result<(), ConfigFileError> {
        let bad = |key: &'static str, value: String, why: String| ConfigFileError::Invalid {
            path: path.to_owned(),
            key,
            value,
            why,
        };
        let h = &self.hebi;
        if !(h.lookup_timeout_s.is_finite() && (0.01..=60.0).contains(&h.lookup_timeout_s)) {
            return Err(bad(
                "hebi.lookup_timeout_s",
                Num(h.lookup_timeout_s).to_string(),
                "must be in [0.01, 60]".into(),
            ));
        }
        for i in &h.interfaces {
            if i.parse::<std::net::Ipv4Addr>().is_err() {
                return Err(bad(
                    "hebi.interfaces",
                    format!("{i:?}"),
                    "must be IPv4 addresses such as \"10.10.1.255\" or \"127.0.0.1\"".into(),
                ));
            }
        }
        for (role, set) in [
            ("all", &h.gains.all),
            ("lateral", &h.gains.lateral),
            ("dorsal", &h.gains.dorsal),
        ] {
            if let Err((key, why)) = gains::check(set) {
                return Err(bad("hebi.gains", format!("{role}.{key}"), why));
            }
        }
        if self.bus.kind != BusChoice::Hebi {
            return Ok(());
        }
        if self.loop_.pacing != super::config::Pacing::Realtime {
            return Err(bad(
                "loop.pacing",
                "lockstep".into(),
                "bus.kind = \"hebi\" runs real-time: libhebi paces its own feedback".into(),
            ));
        }
        let n = h.module_count();
        if n == 0 {
            return Err(bad(
                "hebi.modules",
                "0".into(),
                "name the modules (hebi.names), give how many of the family (hebi.modules), \
                 or hebi.imitation"
                    .into(),
            ));
        }
        crate::bus::hebi::lookup::order_for(&h.order, n)
            .map_err(|why| bad("hebi.order", format!("{:?}", h.order), why))?;
        let configured = (!h.library.as_os_str().is_empty()).then_some(h.library.as_path());
        let lib = crate::bus::hebi::library::find(configured)
            .and_then(|p| crate::bus::hebi::library::load(&p));
        if let Err(e) = lib {
            return Err(bad(
                "hebi.library",
                h.library.display().to_string(),
                e.to_string(),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refused(text: &str) -> String {
        Config::parse(text, Path::new("x.toml"))
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn hebi_keys_are_checked_with_their_names() {
        let hebi = "[bus]\nkind = \"hebi\"\n[hebi]\nimitation = 4\n";
        let e = refused(&format!("{hebi}order = [0, 1, 1, 3]\n"));
        assert!(e.contains("hebi.order") && e.contains("once"), "{e}");
        let e = refused(&format!("{hebi}order = [0, 1]\n"));
        assert!(
            e.contains("hebi.order") && e.contains("2 entries for 4"),
            "{e}"
        );
        let e = refused(&format!("{hebi}[loop]\npacing = \"lockstep\"\n"));
        assert!(e.contains("loop.pacing") && e.contains("libhebi"), "{e}");
        let e = refused("[bus]\nkind = \"hebi\"\n[hebi]\nmodules = 0\n");
        assert!(e.contains("hebi.modules"), "{e}");
        let e = refused(&format!(
            "{hebi}library = \"/nonexistent/libhebi.so.2.27.0\"\n"
        ));
        assert!(
            e.contains("hebi.library") && e.contains("/nonexistent/libhebi.so.2.27.0"),
            "{e}"
        );
        // Keys every bus checks, whether or not the HEBI bus is chosen.
        let e = refused("[hebi]\ninterfaces = [\"eth0\"]\n");
        assert!(e.contains("hebi.interfaces") && e.contains("eth0"), "{e}");
        let e = refused("[hebi.gains.dorsal]\nvelocity_kp = -2.0\n");
        assert!(
            e.contains("hebi.gains") && e.contains("dorsal.velocity_kp"),
            "{e}"
        );
        let e = refused("[hebi.gains.all]\nposition_gain = 1.0\n");
        assert!(
            e.contains("all.position_gain") && e.contains("not a gain"),
            "{e}"
        );
        let e = refused("[hebi]\nlookup_timeout_s = 0.0\n");
        assert!(e.contains("hebi.lookup_timeout_s"), "{e}");
        let e = refused("[bus]\nkind = \"can\"\n");
        assert!(e.contains("kind") && e.contains("hebi"), "{e}");
    }

    #[test]
    fn the_module_count_follows_the_source() {
        let mut h = HebiConfig::default();
        assert_eq!(h.module_count(), 18);
        h.names = vec!["a".into(), "b".into()];
        assert_eq!(h.module_count(), 2);
        h.imitation = 5;
        assert_eq!(h.module_count(), 5);
    }
}
