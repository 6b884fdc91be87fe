//! What every bus counts for the statistics, and a bus's own counters by name.

use serde::ser::{Serialize, SerializeMap, Serializer};

/// Room for a bus's own counters ([`CounterSet`]).
pub const MAX_DETAIL: usize = 16;

/// Counters a bus keeps for the statistics; monotonically increasing. `Copy`: the
/// loop copies them into its telemetry every cycle without allocating.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct BusCounters {
    pub feedback_received: u64,
    /// Feedback the modules sent that never arrived (sequence gaps).
    pub feedback_lost: u64,
    /// Feedback not newer than the newest held (replayed or reordered).
    pub feedback_replayed: u64,
    pub commands_sent: u64,
    /// Sends that failed (socket full, unreachable).
    pub send_errors: u64,
    /// Incoming data dropped as unusable, for any reason (`detail` says which).
    pub dropped: u64,
    /// The bus's own counters, by name (UDP: why datagrams were dropped).
    pub detail: CounterSet,
}

/// A fixed set of named counters, its names chosen by the bus that keeps it.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct CounterSet {
    names: &'static [&'static str],
    values: [u64; MAX_DETAIL],
}

impl Default for CounterSet {
    fn default() -> Self {
        Self::new(&[])
    }
}

impl CounterSet {
    /// All zero. Panics with more than [`MAX_DETAIL`] names (a bus's fixed choice).
    pub const fn new(names: &'static [&'static str]) -> Self {
        assert!(names.len() <= MAX_DETAIL, "too many bus counters");
        Self {
            names,
            values: [0; MAX_DETAIL],
        }
    }

    /// Sets the counter at `index` of the names given to [`CounterSet::new`].
    pub fn set(&mut self, index: usize, value: u64) {
        self.values[index] = value;
    }

    /// The counter called `name`, if the bus keeps one.
    pub fn get(&self, name: &str) -> Option<u64> {
        self.iter().find(|(n, _)| *n == name).map(|(_, v)| v)
    }

    /// Names and values, in the bus's order.
    pub fn iter(&self) -> impl Iterator<Item = (&'static str, u64)> + '_ {
        self.names.iter().copied().zip(self.values.iter().copied())
    }
}

impl std::fmt::Debug for CounterSet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_map().entries(self.iter()).finish()
    }
}

impl Serialize for CounterSet {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.names.len()))?;
        for (name, value) in self.iter() {
            map.serialize_entry(name, &value)?;
        }
        map.end()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_set_serialises_as_its_names_and_finds_them() {
        const NAMES: &[&str] = &["bad_tag", "unexpected"];
        let mut set = CounterSet::new(NAMES);
        set.set(1, 4);
        assert_eq!(set.get("unexpected"), Some(4));
        assert_eq!(set.get("bad_tag"), Some(0));
        assert_eq!(set.get("v1_refused"), None);
        let json = serde_json::to_value(set).expect("serialises");
        assert_eq!(json, serde_json::json!({"bad_tag": 0, "unexpected": 4}));
        assert_eq!(format!("{set:?}"), r#"{"bad_tag": 0, "unexpected": 4}"#);
    }
}
