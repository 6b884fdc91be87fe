//! Defaults, validation and patches.
use super::*;

#[test]
fn every_default_gait_is_valid() {
    let table = GaitTable::default();
    for kind in GaitKind::ALL {
        table
            .get(kind)
            .validate(kind)
            .unwrap_or_else(|e| panic!("{kind:?}: {e}"));
    }
    assert_eq!(table.validate_for(MODULE_LENGTH_M), Ok(()));
    // Thesis values where it gives them, but sidewinding's waves in quadrature (the
    // reversal's wells then run forward and backward alike; the thesis's 3π/4 stalls
    // inside one).
    let sw = table.get(GaitKind::Sidewinding);
    assert_eq!(sw.phase_shift_rad, PI / 2.0);
    assert_eq!(table.get(GaitKind::Slithering).spatial_freq_rad, 3.0 * PI);
}

#[test]
fn kind_names_round_trip() {
    for kind in GaitKind::ALL {
        assert_eq!(GaitKind::from_name(kind.name()), Some(kind));
        assert_eq!(GaitKind::ALL[kind.index()], kind);
    }
    assert_eq!(GaitKind::from_name("moonwalk"), None);
}

#[test]
fn non_finite_fields_are_refused_even_when_unused() {
    for kind in GaitKind::ALL {
        for field in Field::ALL {
            for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                let mut p = GaitParams::default_for(kind);
                field.set(&mut p, bad);
                assert_eq!(
                    p.validate(kind),
                    Err(ParamError::NotFinite {
                        field: field.name()
                    }),
                    "{kind:?} {field:?}"
                );
            }
        }
    }
}

#[test]
fn used_fields_out_of_range_are_refused() {
    let kind = GaitKind::ConicalSidewinding;
    let cases = [
        (Field::AmplitudeLat, -0.1),
        (Field::AmplitudeDor, 1.6),
        (Field::SpatialFreq, 7.0 * PI),
        (Field::TemporalFreq, 11.0),
        (Field::PhaseShift, 7.0),
        (Field::Taper, 0.81),
        (Field::Taper, -0.81),
        (Field::OffsetLat, -1.6),
    ];
    for (field, value) in cases {
        let mut p = GaitParams::default_for(kind);
        field.set(&mut p, value);
        match p.validate(kind) {
            Err(ParamError::OutOfRange { field: f, .. }) => assert_eq!(f, field.name()),
            other => panic!("{field:?} = {value}: {other:?}"),
        }
    }
    // Helix sanity bounds.
    for (field, value) in [(Field::HelixRadius, 0.0), (Field::HelixPitch, -0.01)] {
        let mut p = GaitParams::default_for(GaitKind::RollingHelix);
        field.set(&mut p, value);
        assert!(matches!(
            p.validate(GaitKind::RollingHelix),
            Err(ParamError::OutOfRange { .. })
        ));
    }
}

#[test]
fn taper_of_exactly_point_eight_is_allowed() {
    for c in [0.8, -0.8] {
        let mut p = GaitParams::default_for(GaitKind::ConicalSidewinding);
        p.taper = c;
        assert_eq!(p.validate(GaitKind::ConicalSidewinding), Ok(()));
    }
}

#[test]
fn unused_fields_are_not_range_checked() {
    // Slithering ignores the helix radius, so 0 there is fine.
    let p = GaitParams::default_for(GaitKind::Slithering);
    assert_eq!(p.helix_radius_m, 0.0);
    assert_eq!(p.validate(GaitKind::Slithering), Ok(()));
}

#[test]
fn too_fast_gaits_are_refused_with_a_message_naming_the_limit() {
    let mut p = GaitParams::default_for(GaitKind::Slithering);
    p.temporal_freq_rad_s = 5.0; // π/4 · 5 = 3.93 rad/s > 3.46
    let err = p.validate(GaitKind::Slithering).unwrap_err();
    assert!(matches!(err, ParamError::TooFast { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(msg.contains("3.46"), "{msg}");
    assert!(msg.contains("peak joint speed"), "{msg}");
    // Backwards just as fast is refused too; slightly slower passes.
    p.temporal_freq_rad_s = -5.0;
    assert!(p.validate(GaitKind::Slithering).is_err());
    p.temporal_freq_rad_s = 4.3; // 3.38 rad/s
    assert_eq!(p.validate(GaitKind::Slithering), Ok(()));
}

#[test]
fn negative_taper_counts_in_the_speed_and_range_checks() {
    let mut p = GaitParams::default_for(GaitKind::ConicalSidewinding);
    p.temporal_freq_rad_s = 3.0; // π/4 · 3 = 2.36; with taper -0.8: 4.24
    p.taper = 0.0;
    assert_eq!(p.validate(GaitKind::ConicalSidewinding), Ok(()));
    p.taper = -0.8;
    assert!(matches!(
        p.validate(GaitKind::ConicalSidewinding),
        Err(ParamError::TooFast { .. })
    ));
    p.temporal_freq_rad_s = 1.0;
    p.amplitude_lat_rad = 1.0; // 1.8 rad at the tail
    assert!(matches!(
        p.validate(GaitKind::ConicalSidewinding),
        Err(ParamError::JointRange {
            plane: "lateral",
            ..
        })
    ));
}

#[test]
fn offset_plus_amplitude_beyond_joint_range_is_refused() {
    let mut p = GaitParams::default_for(GaitKind::Sidewinding);
    p.offset_dor_rad = 1.3; // + π/8 > π/2
    let err = p.validate(GaitKind::Sidewinding).unwrap_err();
    assert!(
        matches!(
            err,
            ParamError::JointRange {
                plane: "dorsal",
                ..
            }
        ),
        "{err:?}"
    );
}

#[test]
fn too_tight_helix_is_refused_by_its_derived_amplitude() {
    let mut p = GaitParams::default_for(GaitKind::RollingHelix);
    p.helix_radius_m = 0.04;
    p.helix_pitch_m = 0.01; // κ ≈ 23.5 /m: A ≈ 3 rad
    assert!(matches!(
        p.validate(GaitKind::RollingHelix),
        Err(ParamError::JointRange { .. })
    ));
}

#[test]
fn patched_applies_validates_and_leaves_the_original_alone() {
    let p = GaitParams::default_for(GaitKind::Sidewinding);
    let patch = ParamPatch {
        amplitude_lat_rad: Some(0.5),
        temporal_freq_rad_s: Some(-0.8),
        ..ParamPatch::default()
    };
    let q = p
        .patched(GaitKind::Sidewinding, &patch)
        .expect("valid patch");
    assert_eq!(q.amplitude_lat_rad, 0.5);
    assert_eq!(q.temporal_freq_rad_s, -0.8);
    assert_eq!(q.phase_shift_rad, p.phase_shift_rad);
    assert_eq!(p, GaitParams::default_for(GaitKind::Sidewinding));
    // An empty patch returns the same set.
    assert_eq!(
        p.patched(GaitKind::Sidewinding, &ParamPatch::default()),
        Ok(p)
    );
}

#[test]
fn patched_refuses_bad_values() {
    let p = GaitParams::default_for(GaitKind::Slithering);
    let nan = ParamPatch {
        spatial_freq_rad: Some(f64::NAN),
        ..ParamPatch::default()
    };
    assert_eq!(
        p.patched(GaitKind::Slithering, &nan),
        Err(ParamError::NotFinite {
            field: "spatial_freq_rad"
        })
    );
    let fast = ParamPatch {
        temporal_freq_rad_s: Some(9.0),
        ..ParamPatch::default()
    };
    assert!(matches!(
        p.patched(GaitKind::Slithering, &fast),
        Err(ParamError::TooFast { .. })
    ));
}

#[test]
fn patched_refuses_changes_to_fields_the_gait_ignores() {
    let p = GaitParams::default_for(GaitKind::Rolling);
    let patch = ParamPatch {
        spatial_freq_rad: Some(2.0),
        ..ParamPatch::default()
    };
    let err = p.patched(GaitKind::Rolling, &patch).unwrap_err();
    assert_eq!(
        err,
        ParamError::Unused {
            gait: "rolling",
            field: "spatial_freq_rad"
        }
    );
    assert_eq!(err.to_string(), "rolling does not use spatial_freq_rad");
    // Re-sending the current value is fine.
    let same = ParamPatch {
        spatial_freq_rad: Some(p.spatial_freq_rad),
        ..ParamPatch::default()
    };
    assert_eq!(p.patched(GaitKind::Rolling, &same), Ok(p));
}

#[test]
fn every_field_is_used_by_some_gait_and_round_trips_through_set_get() {
    for field in Field::ALL {
        assert!(GaitKind::ALL.iter().any(|k| k.uses(field)), "{field:?}");
        let mut p = GaitParams::default();
        field.set(&mut p, 0.123);
        assert_eq!(field.get(&p), 0.123);
    }
}

#[test]
fn module_length_changes_the_helix_check() {
    // Same r, p: longer modules bend each joint further.
    let mut p = GaitParams::default_for(GaitKind::RollingHelix);
    p.helix_radius_m = 0.08;
    p.helix_pitch_m = 0.03;
    assert_eq!(p.validate_for(GaitKind::RollingHelix, 0.064), Ok(()));
    assert!(p.validate_for(GaitKind::RollingHelix, 0.12).is_err());
}

/// Issue 25: |offset| + amplitude one double beyond the joint limit is refused (no
/// tolerance), and messages print the values readably.
#[test]
fn the_joint_range_is_exact_and_messages_readable() {
    let mut p = GaitParams::default_for(GaitKind::Slithering);
    p.offset_lat_rad = 0.5;
    p.amplitude_lat_rad = JOINT_LIMIT_RAD - 0.5;
    assert!(0.5 + p.amplitude_lat_rad <= JOINT_LIMIT_RAD);
    p.temporal_freq_rad_s = 0.5;
    assert_eq!(p.validate(GaitKind::Slithering), Ok(()));
    p.amplitude_lat_rad = p.amplitude_lat_rad.next_up();
    assert!(0.5 + p.amplitude_lat_rad > JOINT_LIMIT_RAD);
    assert!(matches!(
        p.validate(GaitKind::Slithering),
        Err(ParamError::JointRange { .. })
    ));
    let patch = ParamPatch {
        temporal_freq_rad_s: Some(-1e308),
        ..ParamPatch::default()
    };
    let e = GaitParams::default_for(GaitKind::Slithering)
        .patched(GaitKind::Slithering, &patch)
        .unwrap_err()
        .to_string();
    assert!(e.contains("-1e308") && e.len() < 100, "{e}");
}
