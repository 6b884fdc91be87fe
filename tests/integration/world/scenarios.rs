//! Every example in `scenarios/` loads and generates a world for an 18-module snake.

use std::path::Path;

use snaked::emu::world::scenario::WorldScenario;

#[test]
fn every_example_scenario_generates() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let mut names = Vec::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let s = WorldScenario::load(&path).unwrap_or_else(|e| panic!("{e}"));
            let w = s.generate(18).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(w, s.generate(18).unwrap(), "{}", path.display());
            assert!(w.ground, "{}", path.display());
            // Several trials for random starts.
            for k in 1..4 {
                s.generate_trial(18, k).unwrap_or_else(|e| panic!("{e}"));
            }
            names.push(path.file_name().unwrap().to_string_lossy().into_owned());
        }
    }
    names.sort();
    assert_eq!(
        names,
        [
            "flat.toml",
            "peg-array.toml",
            "peg-board-40-inside.toml",
            "peg-board-40-sleeve.toml",
            "peg-board-40.toml",
            "peg-row.toml",
            "pole.toml",
            "rock-pile-3d.toml",
            "rock-pile.toml",
            "sidewinding-pegs.toml",
            "walls.toml"
        ]
    );
}

#[test]
fn examples_have_what_they_say() {
    let load = |n: &str| {
        let p = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenarios")
            .join(n);
        WorldScenario::load(&p).unwrap().generate(18).unwrap()
    };
    assert_eq!(load("peg-board-40.toml").pegs.len(), 40);
    // The sleeve's board is the thesis board with the sleeve's low friction on the
    // pegs and the ground alike.
    let sleeve = load("peg-board-40-sleeve.toml");
    assert_eq!(sleeve.friction.peg_mu, Some(0.2));
    assert_eq!(sleeve.friction.mu, 0.2);
    assert_eq!(sleeve.pegs, load("peg-board-40-inside.toml").pegs);
    assert_eq!(load("peg-row.toml").pegs.len(), 10);
    let pole = load("pole.toml");
    let d: Vec<f64> = pole.poles[0]
        .sections
        .iter()
        .map(|s| s.diameter_m)
        .collect();
    assert_eq!(d, [0.10, 0.08, 0.12]);
    assert_eq!(load("rock-pile.toml").rocks.len(), 30);
    assert_eq!(load("rock-pile-3d.toml").rocks.len(), 130);
    assert_eq!(load("peg-array.toml").pegs.len(), 270);
    assert_eq!(load("walls.toml").walls.len(), 5);
}
