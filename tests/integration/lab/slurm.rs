//! `scripts/lab-slurm.sh` against a stub `sbatch` (no Slurm here): the stub records
//! every submission and runs it as Slurm would once its dependency allows (an array's
//! tasks one by one, a job depending `afterok` only if every task succeeded, `afterany`
//! once they all ended), so a failing shard shows whether the merge runs and what it says.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::read;

/// The stub: job ids from 101; an array's tasks and a job's status in `$STUB_DIR`.
const SBATCH: &str = r#"#!/usr/bin/env bash
set -u
dir=$STUB_DIR
k=$(( $(ls "$dir" | grep -c '^call-') + 1 ))
printf '%s\0' "$@" > "$dir/call-$k"
id=$((100 + k))
array= wrap= output= dep=
for a in "$@"; do
    case $a in
        --array=*) array=${a#--array=} ;;
        --wrap=*) wrap=${a#--wrap=} ;;
        --output=*) output=${a#--output=} ;;
        --dependency=*) dep=${a#--dependency=} ;;
    esac
done
if [ -n "$array" ]; then
    failed=0
    for t in $(seq "${array%-*}" "${array#*-}"); do
        out=${output//%a/$t}
        SLURM_ARRAY_TASK_ID=$t sh -c "$wrap" > "$out" 2>&1 || failed=1
    done
    echo "$failed" > "$dir/failed-$id"
else
    kind=${dep%%:*} after=${dep#*:}
    if [ "$kind" = afterok ] && [ "$(cat "$dir/failed-$after")" = 1 ]; then
        echo "PD DependencyNeverSatisfied" > "$dir/state-$id"
    else
        sh -c "$wrap" > "$output" 2>&1
        echo "exit $?" > "$dir/state-$id"
    fi
fi
echo "$id"
"#;

/// A stub directory with `sbatch` on its PATH, and a `snake-lab` that dies as shard 2/3.
fn stubs(dir: &Path) -> (PathBuf, PathBuf) {
    use std::os::unix::fs::PermissionsExt;
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let exe = |p: &Path, text: &str| {
        std::fs::write(p, text).unwrap();
        std::fs::set_permissions(p, std::fs::Permissions::from_mode(0o755)).unwrap();
    };
    exe(&bin.join("sbatch"), SBATCH);
    let lab = dir.join("dying-lab");
    exe(
        &lab,
        &format!(
            "#!/bin/sh\ncase \" $* \" in *' --shard 2/3 '*) echo 'killed: out of memory' >&2; exit 137 ;; esac\nexec '{}' \"$@\"\n",
            env!("CARGO_BIN_EXE_snake-lab")
        ),
    );
    (bin, lab)
}

/// Runs the script with the stubs, `lab` as LAB, into `out`; returns its exit code,
/// its stdout and stderr.
fn submit(dir: &Path, bin: &Path, lab: &Path, out: &Path) -> (Option<i32>, String) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/lab-slurm.sh");
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap());
    let o = Command::new("bash")
        .arg(script)
        .args([
            "pegboard",
            "--controllers",
            "open_loop",
            "--layouts",
            "3",
            "--starts",
            "1",
            "--seconds",
            "1",
        ])
        .env("PATH", path)
        .env("STUB_DIR", dir)
        .env("N", "3")
        .env("OUT", out)
        .env("LAB", lab)
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    (o.status.code(), text)
}

/// The arguments of the stub's `k`-th call.
fn call(dir: &Path, k: usize) -> Vec<String> {
    let bytes = std::fs::read(dir.join(format!("call-{k}"))).unwrap();
    String::from_utf8(bytes)
        .unwrap()
        .split_terminator('\0')
        .map(str::to_owned)
        .collect()
}

#[test]
fn a_failed_shard_does_not_leave_the_merge_pending_and_the_merge_names_it() {
    let dir = tempfile::tempdir().unwrap();
    let (bin, lab) = stubs(dir.path());
    let out = dir.path().join("sweep");
    let (code, text) = submit(dir.path(), &bin, &lab, &out);
    assert_eq!(code, Some(0), "{text}");
    assert!(
        text.contains("shards: job 101 (array 1-3), merge: job 102"),
        "{text}"
    );
    let array = call(dir.path(), 1);
    assert!(array.iter().any(|a| a == "--array=1-3"), "{array:?}");
    let merge = call(dir.path(), 2);
    assert!(
        merge.iter().any(|a| a == "--dependency=afterany:101"),
        "the merge waits for every task however it ended: {merge:?}"
    );
    // It ran, failed, and said which shard and where its log is.
    let state = read(&dir.path().join("state-102"));
    assert_eq!(state.trim(), "exit 2", "{state}");
    let log = read(&out.join("logs/merge.log"));
    assert!(
        log.contains("1 of 3 shards missing: 2/3 (have 1/3, 3/3)"),
        "{log}"
    );
    let shard_log = out.join("logs/shard-2.log");
    assert!(
        log.contains(&format!(
            "shard 2/3 wrote no file: see {}",
            shard_log.display()
        )),
        "{log}"
    );
    assert!(read(&shard_log).contains("killed: out of memory"));
    assert!(!out.join("results.csv").exists());

    // An OUT with an earlier run in it is refused before anything is submitted.
    let (code, text) = submit(dir.path(), &bin, &lab, &out);
    assert_eq!(code, Some(2), "{text}");
    assert!(text.contains("is not empty"), "{text}");
    assert!(!dir.path().join("call-3").exists());

    // Every shard done: the merge writes the report.
    let fine = dir.path().join("sweep-ok");
    let real = PathBuf::from(env!("CARGO_BIN_EXE_snake-lab"));
    let (code, text) = submit(dir.path(), &bin, &real, &fine);
    assert_eq!(code, Some(0), "{text}");
    assert_eq!(read(&dir.path().join("state-104")).trim(), "exit 0");
    assert_eq!(read(&fine.join("results.csv")).lines().count(), 4);
}
