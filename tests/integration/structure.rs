//! The crate's layout: no two folders of `src/` depend on each other, directly or round
//! a cycle (`scripts/folder-cycles.py`, which docs/architecture.md's folder table cites).

use std::path::Path;
use std::process::{Command, Output};

fn folder_cycles(src: &Path) -> Output {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/folder-cycles.py");
    Command::new("python3")
        .arg(script)
        .arg(src)
        .output()
        .expect("python3 runs scripts/folder-cycles.py")
}

#[test]
fn no_folder_of_src_depends_back_on_one_that_depends_on_it() {
    let out = folder_cycles(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "scripts/folder-cycles.py: {}\n{text}{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("mutual pairs (0)"), "{text}");
    assert!(
        text.contains("cycles (strongly connected groups of folders, 0)"),
        "{text}"
    );
}

#[test]
fn the_check_fails_on_a_cycle() {
    // Two folders naming each other, one of them only inside a `use crate::{..}` group.
    let src = tempfile::tempdir().unwrap();
    for (folder, code) in [
        ("a", "use crate::b::Thing;\n"),
        ("b", "use crate::{a::Other, num};\n"),
        ("c", "use crate::a::Other;\n"),
    ] {
        std::fs::create_dir(src.path().join(folder)).unwrap();
        std::fs::write(src.path().join(folder).join("mod.rs"), code).unwrap();
    }
    let out = folder_cycles(src.path());
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(text.contains("mutual pairs (1): a <-> b"), "{text}");
    assert!(
        text.contains("cycles (strongly connected groups of folders, 1): a b"),
        "{text}"
    );
}
