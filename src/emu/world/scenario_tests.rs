use super::*;
use crate::emu::world::generators::{body_hits, point_segment_m, serpenoid_geometry};
use crate::module::MODULE_RADIUS_M;

const BOARD: &str = r#"
seed = 7
[[peg_board]]
count = 40
diameter_m = 0.04
min_spacing_m = 0.16
region = { x_m = [0.0, 2.0], y_m = [-0.6, 0.6] }
"#;

fn parse(text: &str) -> WorldScenario {
    WorldScenario::parse(text).unwrap()
}

fn err(text: &str) -> String {
    match WorldScenario::parse(text) {
        Ok(s) => s.generate(18).unwrap_err().to_string(),
        Err(e) => e.to_string(),
    }
}

#[test]
fn empty_file_is_flat_ground_with_the_default_start() {
    let w = parse("").generate(18).unwrap();
    assert_eq!(w, WorldSpec::default());
}

#[test]
fn same_seed_same_world_different_seed_different_world() {
    let a = parse(BOARD).generate(18).unwrap();
    let b = parse(BOARD).generate(18).unwrap();
    assert_eq!(a, b);
    assert_eq!(a.pegs.len(), 40);
    let c = parse(&BOARD.replace("seed = 7", "seed = 8"))
        .generate(18)
        .unwrap();
    assert_ne!(a.pegs, c.pegs);
    // A per-board seed overrides the master seed.
    let over = format!("{BOARD}seed = 99\n");
    let d = parse(&over).generate(18).unwrap();
    let e = parse(&over.replace("seed = 7", "seed = 1"))
        .generate(18)
        .unwrap();
    assert_eq!(d.pegs, e.pegs);
    assert_ne!(d.pegs, a.pegs);
}

#[test]
fn adding_a_generator_does_not_reshuffle_another() {
    let a = parse(BOARD).generate(18).unwrap();
    let more = format!(
        "{BOARD}\n[[rock_pile]]\ncount = 5\nsize_m = [0.05, 0.1]\n\
         region = {{ x_m = [3.0, 4.0], y_m = [0.0, 1.0] }}\n\
         [[peg_board]]\ncount = 3\ndiameter_m = 0.02\nmin_spacing_m = 0.1\n\
         region = {{ x_m = [5.0, 6.0], y_m = [0.0, 1.0] }}\n"
    );
    let b = parse(&more).generate(18).unwrap();
    assert_eq!(b.pegs[..40], a.pegs[..]);
    assert_eq!(b.pegs.len(), 43);
}

#[test]
fn min_spacing_respected_and_pegs_in_region() {
    for seed in 0..5 {
        let w = parse(&BOARD.replace("seed = 7", &format!("seed = {seed}")))
            .generate(18)
            .unwrap();
        for (i, p) in w.pegs.iter().enumerate() {
            assert!(
                (0.0..=2.0).contains(&p.x_m) && (-0.6..=0.6).contains(&p.y_m),
                "{p:?}"
            );
            assert_eq!((p.diameter_m, p.height_m), (0.04, DEFAULT_PEG_HEIGHT_M));
            for q in &w.pegs[i + 1..] {
                let d = (p.x_m - q.x_m).hypot(p.y_m - q.y_m);
                assert!(d >= 0.16, "pegs {p:?} and {q:?} are {d} apart");
            }
        }
    }
}

#[test]
fn impossible_count_is_refused_with_the_fit_count() {
    let text = BOARD.replace("count = 40", "count = 200");
    let e = parse(&text).generate(18).unwrap_err();
    let ScenarioError::PegsDontFit {
        fit,
        count,
        hex,
        ref key,
        ..
    } = e
    else {
        panic!("{e}");
    };
    assert_eq!((count, key.as_str()), (200, "peg_board[0].count"));
    assert!(fit > 30 && fit < 200 && fit <= hex, "fit {fit}, hex {hex}");
    let msg = e.to_string();
    assert!(
        msg.contains(&format!("fits about {fit}")) && msg.contains("200"),
        "{msg}"
    );
}

#[test]
fn pegs_file_is_read_relative_to_the_scenario() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("layouts")).unwrap();
    std::fs::write(
        dir.path().join("layouts/pegs.csv"),
        "x,y,diameter\n# a comment\n0.1, 0.2\n\n0.5,-0.3,0.05 # wide\n",
    )
    .unwrap();
    let path = dir.path().join("world.toml");
    std::fs::write(
        &path,
        "[[peg_file]]\npath = \"layouts/pegs.csv\"\ndiameter_m = 0.03\nheight_m = 0.2\n\
         [start]\nhead_m = [-1.0, 0.0]\n",
    )
    .unwrap();
    let w = WorldScenario::load(&path).unwrap().generate(10).unwrap();
    let got: Vec<_> = w
        .pegs
        .iter()
        .map(|p| (p.x_m, p.y_m, p.diameter_m, p.height_m))
        .collect();
    assert_eq!(got, [(0.1, 0.2, 0.03, 0.2), (0.5, -0.3, 0.05, 0.2)]);

    std::fs::write(dir.path().join("layouts/pegs.csv"), "0.1,0.2\n0.3,abc\n").unwrap();
    let msg = WorldScenario::load(&path)
        .unwrap()
        .generate(10)
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("world.toml") && msg.contains("peg_file[0].path"),
        "{msg}"
    );
    assert!(msg.contains("pegs.csv:2"), "{msg}");
}

#[test]
fn explicit_pegs_and_walls_pass_through() {
    let w = parse(
        "[[peg]]\nx_m = 1.0\ny_m = 2.0\ndiameter_m = 0.05\n\
         [[wall]]\nfrom_m = [0, 1]\nto_m = [2, 1]\nheight_m = 0.2\nthickness_m = 0.02\n",
    )
    .generate(18)
    .unwrap();
    assert_eq!(w.pegs[0].height_m, DEFAULT_PEG_HEIGHT_M);
    assert_eq!(w.walls[0].to_m, [2.0, 1.0]);
}

#[test]
fn pole_sections_become_contiguous_and_are_validated() {
    let w = parse(
        "[[pole]]\nx_m = 0.5\ny_m = 0.5\nsections = [{ top_m = 0.4, diameter_m = 0.1 }, \
         { top_m = 0.8, diameter_m = 0.08 }]\n",
    )
    .generate(18)
    .unwrap();
    let z: Vec<_> = w.poles[0]
        .sections
        .iter()
        .map(|s| (s.z0_m, s.z1_m, s.diameter_m))
        .collect();
    assert_eq!(z, [(0.0, 0.4, 0.1), (0.4, 0.8, 0.08)]);
    assert_eq!(w.poles[0].mu, 0.5);

    let bad = err(
        "[[pole]]\nx_m = 0\ny_m = 0\nsections = [{ top_m = 0.4, diameter_m = 0.1 }, \
                   { top_m = 0.3, diameter_m = 0.08 }]\n",
    );
    assert!(
        bad.contains("pole[0].sections[1].top_m") && bad.contains("not above"),
        "{bad}"
    );
    let neg = err("[[pole]]\nx_m = 0\ny_m = 0\nsections = [{ top_m = 0.4, diameter_m = -0.1 }]");
    assert!(neg.contains("pole[0].sections[0].diameter_m"), "{neg}");
    let both = err("[[pole]]\nx_m = 0\ny_m = 0\nsections = []\n\
                    taper = { height_m = 1, bottom_diameter_m = 0.1, top_diameter_m = 0.05 }");
    assert!(both.contains("exactly one"), "{both}");

    let t = parse("[[pole]]\nx_m = 0.5\ny_m = 0.5\nmu = 0.7\n\
                   taper = { height_m = 1.0, bottom_diameter_m = 0.12, top_diameter_m = 0.08, steps = 4 }")
    .generate(18)
    .unwrap();
    let p = &t.poles[0];
    assert_eq!((p.sections.len(), p.mu), (4, 0.7));
    assert!((p.sections[0].diameter_m - 0.115).abs() < 1e-12);
    assert!((p.sections[3].z1_m - 1.0).abs() < 1e-12);
}

#[test]
fn rocks_lie_in_the_region_and_rest_on_the_ground() {
    let w = parse(
        "seed = 3\n[[rock_pile]]\ncount = 25\nsize_m = [0.06, 0.16]\n\
         region = { x_m = [0.5, 1.5], y_m = [-0.5, 0.5] }\n[start]\nhead_m = [-0.5, 0]\n",
    )
    .generate(18)
    .unwrap();
    assert_eq!(w.rocks.len(), 25);
    for r in &w.rocks {
        let [x, y, z] = r.center_m;
        assert!(
            (0.5..=1.5).contains(&x) && (-0.5..=0.5).contains(&y),
            "{r:?}"
        );
        assert_eq!(r.points_m.len(), 16);
        let low = r
            .points_m
            .iter()
            .map(|p| p[2] + z)
            .fold(f64::INFINITY, f64::min);
        assert!(low.abs() < 1e-12, "lowest point at {low}");
        let reach = r
            .points_m
            .iter()
            .map(|p| p[0].hypot(p[1]))
            .fold(0.0, f64::max);
        assert!(reach > 0.02 && reach < 0.08 * 1.15 + 1e-9, "reach {reach}");
    }
}

#[test]
fn start_intersecting_a_peg_is_rejected() {
    // Head at the origin, body along -x up to 18 × 0.064 = 1.152 m; a peg 3 cm off axis.
    let text = "[[peg]]\nx_m = -0.6\ny_m = 0.03\ndiameter_m = 0.02\n[start]\nhead_m = [0, 0]\n";
    let e = parse(text).generate(18).unwrap_err();
    assert!(matches!(e, ScenarioError::StartBlocked { .. }), "{e}");
    assert!(e.to_string().contains("peg 0"), "{e}");
    // 0.0255 + 0.01 = 0.0355: clear at 4 cm off axis, and past the tail.
    assert!(parse(&text.replace("0.03", "0.04")).generate(18).is_ok());
    assert!(parse(&text.replace("-0.6", "-1.2")).generate(18).is_ok());
    assert!(parse(&text.replace("-0.6", "-1.2")).generate(19).is_err());
    assert!(
        parse(&format!("{text}allow_contact = true\n"))
            .generate(18)
            .is_ok()
    );
}

#[test]
fn random_starts_avoid_pegs_and_vary_by_trial() {
    let text = format!(
        "{BOARD}[start.random]\nregion = {{ x_m = [0.2, 0.5], y_m = [-0.3, 0.3] }}\n\
         yaw_range_rad = [2.8, 3.4]\n"
    );
    let s = parse(&text);
    let w0 = s.generate_trial(18, 0).unwrap();
    let w1 = s.generate_trial(18, 1).unwrap();
    assert_eq!(w0.pegs, w1.pegs);
    assert_ne!(w0.start, w1.start);
    assert_eq!(w0.start, s.generate(18).unwrap().start);
    for w in [&w0, &w1] {
        let [x, y, _] = w.start.head_m;
        assert!(body_hits(w, [x, y], w.start.yaw_rad, 18).is_none());
        assert!((2.8..=3.4).contains(&w.start.yaw_rad));
    }
    // A region packed with pegs leaves no start.
    let packed = "[[peg_board]]\ncount = 30\ndiameter_m = 0.05\nmin_spacing_m = 0.1\n\
                  region = { x_m = [-2, 2], y_m = [-2, 2] }\n[start.random]\n\
                  region = { x_m = [-1, 1], y_m = [-1, 1] }\n";
    assert!(err(&packed.replace("count = 30", "count = 800")).contains("no random start"));
}

#[test]
fn a_peg_fence_has_random_openings_within_its_gaps() {
    let fence = "seed = 3\n[[peg_fence]]\nstart_m = [-2.0, 0.5]\nlength_m = 4.0\n\
                 diameter_m = 0.05\ngap_m = [0.1, 0.4]\njitter_m = 0.02\n";
    let w = parse(fence).generate(18).unwrap();
    assert!(
        w.pegs.len() >= 4.0f64.div_euclid(0.45) as usize,
        "{}",
        w.pegs.len()
    );
    let mut gaps = Vec::new();
    for pair in w.pegs.windows(2) {
        let (a, b) = (&pair[0], &pair[1]);
        assert!((a.y_m - 0.5).abs() <= 0.02 && (b.y_m - 0.5).abs() <= 0.02);
        let free = b.x_m - a.x_m - 0.05;
        assert!((0.1..0.4).contains(&free), "{free}");
        gaps.push(free);
    }
    assert!(w.pegs.last().unwrap().x_m <= 2.0);
    // Irregular: the openings differ; another seed draws others; the same one the same.
    let spread =
        gaps.iter().cloned().fold(0.0, f64::max) - gaps.iter().cloned().fold(1.0, f64::min);
    assert!(spread > 0.15, "{gaps:?}");
    let other = parse(&fence.replace("seed = 3", "seed = 4"))
        .generate(18)
        .unwrap();
    assert_ne!(other.pegs, w.pegs);
    assert_eq!(parse(fence).generate(18).unwrap().pegs, w.pegs);
    assert!(err(&fence.replace("[0.1, 0.4]", "[0.4, 0.1]")).contains("peg_fence[0].gap_m"));
    assert!(err(&fence.replace("[0.1, 0.4]", "[0.0, 0.1]")).contains("peg_fence[0].gap_m"));
}

#[test]
fn peg_row_follows_the_serpenoid() {
    let (lambda, amp) = serpenoid_geometry(18, 1.5, std::f64::consts::FRAC_PI_4);
    // Arc wavelength 0.768 m; the wave is shorter along x and ~8.5 cm wide.
    assert!(lambda > 0.6 && lambda < 0.768, "{lambda}");
    assert!(amp > 0.07 && amp < 0.1, "{amp}");
    let w = parse(
        "[[peg_row]]\nstart_m = [1.0, 0.0]\ndirection_rad = 1.5707963267948966\ncount = 4\n\
         diameter_m = 0.02\nserpenoid = { waves_per_body = 1.5, joint_amplitude_rad = 0.7853981633974483 }\n",
    )
    .generate(18)
    .unwrap();
    let off = amp - MODULE_RADIUS_M - 0.01;
    for (i, p) in w.pegs.iter().enumerate() {
        let side = if i % 2 == 0 { 1.0 } else { -1.0 };
        // Direction +y: "left" is −x.
        assert!((p.x_m - (1.0 - side * off)).abs() < 1e-9, "{p:?}");
        assert!((p.y_m - i as f64 * lambda / 2.0).abs() < 1e-9, "{p:?}");
    }
    let plain =
        parse("[[peg_row]]\nstart_m = [0, 1]\ncount = 3\ndiameter_m = 0.02\nspacing_m = 0.2\n")
            .generate(18)
            .unwrap();
    assert_eq!(plain.pegs[2].x_m, 0.4);
    assert!(
        err("[[peg_row]]\nstart_m = [0, 1]\ncount = 3\ndiameter_m = 0.02\n")
            .contains("exactly one")
    );
    let thin = err(
        "[[peg_row]]\nstart_m = [0, 1]\ncount = 3\ndiameter_m = 0.02\n\
                    wave = { wavelength_m = 0.5, amplitude_m = 0.02 }\n",
    );
    assert!(thin.contains("no peg fits inside"), "{thin}");
}

#[test]
fn unknown_keys_are_refused_with_their_name() {
    for (text, name) in [
        ("sead = 3", "sead"),
        ("[ground]\nenable = true", "enable"),
        (
            "[friction.anisotropic]\nmu_axial = 1\nmu_lateral = 1\nmu_x = 2",
            "mu_x",
        ),
        (&format!("{BOARD}spacing_m = 0.2"), "spacing_m"),
        (
            "[[pole]]\nx_m = 0\ny_m = 0\nsections = [{ top_m = 1, diameter_m = 0.1, z = 1 }]",
            "z",
        ),
        ("[start]\nheading = 1", "heading"),
    ] {
        let msg = WorldScenario::parse(text).unwrap_err().to_string();
        assert!(msg.contains(name), "{name}: {msg}");
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.toml");
    std::fs::write(
        &path,
        "[[wall]]\nfrom_m = [0, 0]\nto_m = [1, 0]\nheight = 1\n",
    )
    .unwrap();
    let msg = WorldScenario::load(&path).unwrap_err().to_string();
    assert!(msg.contains("bad.toml") && msg.contains("height"), "{msg}");
}

#[test]
fn invalid_values_name_the_file_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("neg.toml");
    std::fs::write(
        &path,
        BOARD.replace("diameter_m = 0.04", "diameter_m = -0.04"),
    )
    .unwrap();
    let msg = WorldScenario::load(&path).unwrap_err().to_string();
    assert!(
        msg.contains("neg.toml") && msg.contains("peg_board[0].diameter_m"),
        "{msg}"
    );
    for (text, key) in [
        (BOARD.replace("[0.0, 2.0]", "[2.0, 2.0]"), "peg_board[0].region.x_m"),
        (BOARD.replace("0.16", "0.03"), "peg_board[0].min_spacing_m"),
        ("[friction]\nmu = nan".into(), "friction.mu"),
        ("[friction]\npeg_mu = -0.1".into(), "friction.peg_mu"),
        ("[start]\nhead_m = [0, inf]".into(), "start.head_m"),
        ("[start]\nhead_m = [0]".into(), "start.head_m"),
        ("[[wall]]\nfrom_m = [0, 0]\nto_m = [0, 0]\nheight_m = 1\nthickness_m = 0.1".into(), "wall[0].to_m"),
        ("[[rock_pile]]\ncount = 1\nsize_m = [0.2, 0.1]\nregion = { x_m = [0, 1], y_m = [0, 1] }".into(), "rock_pile[0].size_m"),
        ("[start]\njoint_angles_rad = [0.1, 0.2, 0.3]".into(), "start.joint_angles_rad"),
    ] {
        let msg = match WorldScenario::parse(&text) {
            Ok(s) => s.generate(2).unwrap_err().to_string(),
            Err(e) => e.to_string(),
        };
        assert!(msg.contains(key), "{key}: {msg}");
    }
}

#[test]
fn body_clearance_geometry() {
    assert!((point_segment_m([0.0, 1.0], [-1.0, 0.0], [1.0, 0.0]) - 1.0).abs() < 1e-12);
    assert!((point_segment_m([2.0, 0.0], [-1.0, 0.0], [1.0, 0.0]) - 1.0).abs() < 1e-12);
    let mut w = WorldSpec::default();
    w.walls.push(crate::emu::world::Wall {
        from_m: [-0.5, -1.0],
        to_m: [-0.5, 1.0],
        height_m: 0.2,
        thickness_m: 0.02,
    });
    assert!(body_hits(&w, [0.0, 0.0], std::f64::consts::PI, 18).is_some());
    assert!(body_hits(&w, [0.0, 0.0], 0.0, 18).is_none());
}

#[test]
fn missing_pegs_file_names_it() {
    let s = parse("[[peg_file]]\npath = \"no-such-dir/pegs.csv\"\ndiameter_m = 0.03\n");
    let msg = s.generate(18).unwrap_err().to_string();
    assert!(
        msg.contains("peg_file[0].path") && msg.contains("no-such-dir/pegs.csv"),
        "{msg}"
    );
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(24))]
    /// Any board either meets its spacing and region, or is refused with a fit count
    /// below the request.
    #[test]
    fn boards_meet_spacing_or_are_refused(
        seed in 0u64..1000,
        count in 1usize..60,
        spacing in 0.05f64..0.4,
        w in 0.2f64..2.0,
        h in 0.2f64..2.0,
    ) {
        let text = format!(
            "seed = {seed}\n[[peg_board]]\ncount = {count}\ndiameter_m = 0.02\n\
             min_spacing_m = {spacing}\nregion = {{ x_m = [0.0, {w}], y_m = [0.0, {h}] }}\n\
             [start]\nhead_m = [-5.0, -5.0]\n"
        );
        match parse(&text).generate(18) {
            Ok(world) => {
                proptest::prop_assert_eq!(world.pegs.len(), count);
                for (i, p) in world.pegs.iter().enumerate() {
                    proptest::prop_assert!(p.x_m >= 0.0 && p.x_m <= w && p.y_m >= 0.0 && p.y_m <= h);
                    for q in &world.pegs[i + 1..] {
                        proptest::prop_assert!((p.x_m - q.x_m).hypot(p.y_m - q.y_m) >= spacing);
                    }
                }
            }
            Err(ScenarioError::PegsDontFit { fit, hex, .. }) => {
                proptest::prop_assert!(fit < count && fit <= hex);
            }
            Err(e) => proptest::prop_assert!(false, "{}", e),
        }
    }
}
