//! Sweeps split over a cluster's scheduler: a run's trial plan is deterministic, so
//! `--shard K/N` runs trials `K-1, K-1+N, K-1+2N, …` of it and writes them, with the
//! configured experiment and how the run was made, to `shard-K-of-N.cbor` (CBOR keeps
//! NaN signals and every bit of every figure); `snake-lab merge` reads the N files
//! back and writes the report one unsharded run would have written. Every shard
//! records the plan's fingerprint, so shards of different runs are never merged.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::LabError;
use super::experiment::Experiment;
use super::report::SummaryContext;
use super::runner::TrialResult;

/// Which share of a run's trials: the `k`-th of `n` (1-based, as `K/N` is written).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    pub k: usize,
    pub n: usize,
}

impl Shard {
    /// Whether trial `index` of the plan (0-based, plan order) is this shard's.
    pub fn owns(&self, index: usize) -> bool {
        index % self.n == self.k - 1
    }

    /// The file a shard writes into its output directory.
    pub fn file_name(&self) -> String {
        format!("shard-{}-of-{}.cbor", self.k, self.n)
    }
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("expected K/N with 1 <= K <= N (e.g. 2/8), not {s:?}");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let k: usize = k.trim().parse().map_err(|_| bad())?;
        let n: usize = n.trim().parse().map_err(|_| bad())?;
        if n == 0 || k == 0 || k > n {
            return Err(bad());
        }
        Ok(Self { k, n })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.k, self.n)
    }
}

/// What every shard file starts with: enough to group, check and dispatch it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShardHead {
    /// [`FORMAT`] when written.
    pub format: u32,
    /// The experiment's subcommand (`snake-lab list`).
    pub experiment: String,
    pub shard: Shard,
    /// Trials in the whole plan.
    pub trials: usize,
    /// A hash of the whole plan (experiment, controllers as built, layouts, starts,
    /// repeats, trial configuration): equal in every shard of one run.
    pub plan: u64,
}

/// The file format's version; a reader refuses others.
pub const FORMAT: u32 = 1;

/// A whole shard file of experiment `E`.
#[derive(Serialize, Deserialize)]
#[serde(bound = "")]
pub struct ShardFile<E: Experiment> {
    pub head: ShardHead,
    /// The experiment as configured (its report needs it).
    pub module: E,
    /// How the run was made, for the summary (the command without `--shard`).
    pub context: SummaryContext,
    /// This shard's trials, with their index in the plan.
    pub results: Vec<(usize, TrialResult<E>)>,
}

/// Writes `file` into `dir` (created if missing) as `shard-K-of-N.cbor`; returns its path.
pub fn write<E: Experiment>(dir: &Path, file: &ShardFile<E>) -> Result<PathBuf, LabError> {
    std::fs::create_dir_all(dir).map_err(|source| LabError::Io {
        path: dir.to_owned(),
        source,
    })?;
    let path = dir.join(file.head.shard.file_name());
    // Written aside and renamed: a shard killed mid-write leaves no file to merge.
    let partial = dir.join(format!(".{}.partial", file.head.shard.file_name()));
    let io = |source| LabError::Io {
        path: partial.clone(),
        source,
    };
    let out = std::fs::File::create(&partial).map_err(io)?;
    let mut out = std::io::BufWriter::new(out);
    ciborium::into_writer(file, &mut out).map_err(|e| LabError::Shard {
        path: partial.clone(),
        msg: e.to_string(),
    })?;
    std::io::Write::flush(&mut out).map_err(io)?;
    std::fs::rename(&partial, &path).map_err(|source| LabError::Io {
        path: path.clone(),
        source,
    })?;
    Ok(path)
}

/// The shard files named by `paths`: a file as is, a directory's `shard-*-of-*.cbor`.
/// None is an error; with `expect` (the run's shard count, `merge --expect N`) it names
/// every shard as missing.
pub fn find(paths: &[PathBuf], expect: Option<usize>) -> Result<Vec<PathBuf>, LabError> {
    let mut files = Vec::new();
    for p in paths {
        if p.is_dir() {
            let entries = std::fs::read_dir(p).map_err(|source| LabError::Io {
                path: p.clone(),
                source,
            })?;
            let mut here: Vec<PathBuf> = entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|f| {
                    f.file_name()
                        .and_then(|n| n.to_str())
                        .is_some_and(|n| n.starts_with("shard-") && n.ends_with(".cbor"))
                })
                .collect();
            here.sort();
            files.extend(here);
        } else if p.is_file() {
            files.push(p.clone());
        } else {
            return Err(LabError::BadValue(format!(
                "{}: no such shard file or directory",
                p.display()
            )));
        }
    }
    if files.is_empty() {
        let dirs = paths
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ");
        return Err(LabError::BadValue(match expect {
            Some(n) => format!(
                "{n} of {n} shards missing: {} (no shard files in {dirs})",
                (1..=n)
                    .map(|k| format!("{k}/{n}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            None => format!("no shard files (shard-K-of-N.cbor) in {dirs}"),
        }));
    }
    Ok(files)
}

/// Reads the head of the shard file at `path`.
pub fn read_head(path: &Path) -> Result<ShardHead, LabError> {
    #[derive(Deserialize)]
    struct HeadOnly {
        head: ShardHead,
    }
    let h: HeadOnly = read(path)?;
    if h.head.format != FORMAT {
        return Err(LabError::Shard {
            path: path.to_owned(),
            msg: format!(
                "format {} (this snake-lab reads {FORMAT}): merge with the snake-lab that wrote it",
                h.head.format
            ),
        });
    }
    Ok(h.head)
}

/// Reads a whole shard file of experiment `E`.
pub fn read_file<E: Experiment>(path: &Path) -> Result<ShardFile<E>, LabError> {
    read(path)
}

fn read<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, LabError> {
    let f = std::fs::File::open(path).map_err(|source| LabError::Io {
        path: path.to_owned(),
        source,
    })?;
    ciborium::from_reader(std::io::BufReader::new(f)).map_err(|e| LabError::Shard {
        path: path.to_owned(),
        msg: format!("not a shard file or damaged: {e}"),
    })
}

/// Checks that `heads` (with their paths) are every shard of one run, once each:
/// the same experiment, plan and shard count (`expect`'s, when given), none missing
/// or twice. Names the missing shards.
pub fn check_complete(
    heads: &[(PathBuf, ShardHead)],
    expect: Option<usize>,
) -> Result<(), LabError> {
    let Some((first_path, first)) = heads.first() else {
        return Err(LabError::BadValue("no shard files".into()));
    };
    if let Some(n) = expect
        && first.shard.n != n
    {
        return Err(LabError::BadValue(format!(
            "{} is shard {} of a {}-shard run, not of {n}",
            first_path.display(),
            first.shard,
            first.shard.n
        )));
    }
    for (p, h) in heads {
        let same = h.experiment == first.experiment
            && h.plan == first.plan
            && h.trials == first.trials
            && h.shard.n == first.shard.n;
        if !same {
            return Err(LabError::BadValue(format!(
                "{} is not of the same run as {} ({} shard {} of a {}-trial plan {:016x}, \
                 against {} shard {} of a {}-trial plan {:016x})",
                p.display(),
                first_path.display(),
                h.experiment,
                h.shard,
                h.trials,
                h.plan,
                first.experiment,
                first.shard,
                first.trials,
                first.plan
            )));
        }
    }
    let n = first.shard.n;
    let mut seen = vec![None::<&Path>; n];
    for (p, h) in heads {
        if let Some(other) = seen[h.shard.k - 1] {
            return Err(LabError::BadValue(format!(
                "shard {} given twice: {} and {}",
                h.shard,
                other.display(),
                p.display()
            )));
        }
        seen[h.shard.k - 1] = Some(p);
    }
    let missing: Vec<String> = (1..=n)
        .filter(|k| seen[k - 1].is_none())
        .map(|k| format!("{k}/{n}"))
        .collect();
    if !missing.is_empty() {
        return Err(LabError::BadValue(format!(
            "{} of {n} shards missing: {} (have {})",
            missing.len(),
            missing.join(", "),
            heads
                .iter()
                .map(|(_, h)| h.shard.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    Ok(())
}

/// The merged trials of `files` (complete, checked), in plan order.
pub fn merge_results<E: Experiment>(
    files: Vec<ShardFile<E>>,
) -> Result<(E, SummaryContext, Vec<TrialResult<E>>), LabError> {
    let mut module_ctx = None;
    let mut all: Vec<(usize, TrialResult<E>)> = Vec::new();
    let mut trials = 0;
    for f in files {
        trials = f.head.trials;
        let shard = f.head.shard;
        let owned = (0..trials).filter(|&i| shard.owns(i)).count();
        let held = f.results.iter().filter(|(i, _)| shard.owns(*i)).count();
        if held != owned || f.results.len() != owned {
            return Err(LabError::BadValue(format!(
                "shard {shard} is incomplete: it holds {} trials, {held} of its {owned} \
                 (cut short? run it again)",
                f.results.len()
            )));
        }
        all.extend(f.results);
        module_ctx.get_or_insert((f.module, f.context));
    }
    let (module, ctx) = module_ctx.ok_or_else(|| LabError::BadValue("no shard files".into()))?;
    all.sort_by_key(|(i, _)| *i);
    let complete = all.len() == trials && all.iter().enumerate().all(|(k, (i, _))| k == *i);
    if !complete {
        return Err(LabError::BadValue(format!(
            "the shards hold {} trials of a {trials}-trial plan (a shard was cut short?)",
            all.len()
        )));
    }
    Ok((module, ctx, all.into_iter().map(|(_, r)| r).collect()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn head(k: usize, n: usize, plan: u64) -> (PathBuf, ShardHead) {
        (
            PathBuf::from(format!("out/shard-{k}-of-{n}.cbor")),
            ShardHead {
                format: FORMAT,
                experiment: "pegboard".into(),
                shard: Shard { k, n },
                trials: 10,
                plan,
            },
        )
    }

    #[test]
    fn k_of_n_parses_and_owns_every_nth_trial() {
        let s: Shard = "2/3".parse().unwrap();
        assert_eq!(s, Shard { k: 2, n: 3 });
        assert_eq!(s.to_string(), "2/3");
        let owned: Vec<usize> = (0..8).filter(|&i| s.owns(i)).collect();
        assert_eq!(owned, [1, 4, 7]);
        for bad in ["0/3", "4/3", "1/0", "3", "a/b", "-1/2", ""] {
            assert!(bad.parse::<Shard>().is_err(), "{bad:?}");
        }
        // Every trial belongs to exactly one shard.
        for i in 0..30 {
            let owners = (1..=4).filter(|&k| Shard { k, n: 4 }.owns(i)).count();
            assert_eq!(owners, 1);
        }
    }

    #[test]
    fn merge_names_missing_duplicate_and_foreign_shards() {
        assert!(check_complete(&[head(1, 3, 7), head(2, 3, 7), head(3, 3, 7)], None).is_ok());
        let e = check_complete(&[head(1, 3, 7), head(3, 3, 7)], None).unwrap_err();
        assert_eq!(e.to_string(), "1 of 3 shards missing: 2/3 (have 1/3, 3/3)");
        let e = check_complete(&[head(1, 2, 7), head(1, 2, 7)], None).unwrap_err();
        assert!(e.to_string().starts_with("shard 1/2 given twice"), "{e}");
        let e = check_complete(&[head(1, 2, 7), head(2, 2, 8)], None).unwrap_err();
        assert!(e.to_string().contains("is not of the same run"), "{e}");
        // Told how many there are (`merge --expect N`): another count is refused.
        let e = check_complete(&[head(1, 2, 7), head(2, 2, 7)], Some(4)).unwrap_err();
        assert!(e.to_string().contains("of a 2-shard run, not of 4"), "{e}");
        assert!(check_complete(&[head(1, 2, 7), head(2, 2, 7)], Some(2)).is_ok());
    }

    #[test]
    fn with_the_count_known_no_file_at_all_names_every_shard() {
        let dir = tempfile::tempdir().unwrap();
        let given = [dir.path().to_owned()];
        let e = find(&given, Some(3)).unwrap_err().to_string();
        assert!(
            e.starts_with("3 of 3 shards missing: 1/3, 2/3, 3/3 (no shard files in "),
            "{e}"
        );
        let e = find(&given, None).unwrap_err().to_string();
        assert!(e.starts_with("no shard files"), "{e}");
    }
}
