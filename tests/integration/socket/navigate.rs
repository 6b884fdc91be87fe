//! `navigate` (issue 28): the navigator turned on and off through the socket and
//! `snakectl`, carried out as an operator's requests, reported in `status`, stopped by
//! an operator's request and refused while it cannot steer.
use std::time::Duration;

use serde_json::{Value, json};
use snaked::socket::api::code;
use snaked::socket::client::{Client, Endpoint};

use super::real::{real_loop, snakectl, status_when};
use crate::support::socket::{Harness, call, error_code, error_message};

#[test]
fn navigate_checks_its_params_and_is_refused_while_it_cannot_steer() {
    let h = Harness::default_server();
    let mut c = h.client();
    for bad in [
        json!({}),
        json!({"heading_rad": 0.5, "off": true}),
        json!({"heading_rad": "north"}),
        json!({"heading_rad": 20.0}),
        json!({"off": "yes"}),
        json!({"off": true, "config": {}}),
        json!({"heading_rad": 0.5, "config": {"bogus": 1}}),
        json!({"heading_rad": 0.5, "config": {"settle_s": -1.0}}),
        json!({"heading_rad": 0.5, "config": []}),
        json!({"heading_rad": 0.5, "config": [60.0]}),
        json!({"heading_rad": 0.5, "speed": 1.0}),
    ] {
        let r = call(&mut c, "navigate", bad.clone());
        assert_eq!(error_code(&r), code::INVALID_PARAMS, "{bad}: {r}");
    }
    // The fake loop starts limp: nothing runs.
    let r = call(&mut c, "navigate", json!({"heading_rad": 0.5}));
    assert_eq!(error_code(&r), code::REFUSED, "{r}");
    assert!(error_message(&r).contains("not running a gait"), "{r}");
    // Running, but its pose estimate never becomes valid.
    call(&mut c, "gait.set", json!({"gait": "slithering"}));
    let r = call(&mut c, "navigate", json!({"heading_rad": 0.5}));
    assert_eq!(error_code(&r), code::REFUSED, "{r}");
    assert!(
        error_message(&r).contains("pose estimate is not valid"),
        "{r}"
    );
    // Off while off is fine and says so.
    let r = call(&mut c, "navigate", json!({"off": true}));
    assert_eq!(
        r["result"],
        json!({"navigating": false, "was_navigating": false})
    );
}

#[test]
fn the_navigator_drives_through_the_loop_reports_itself_and_yields_to_the_operator() {
    let l = real_loop();
    let mut c = Client::connect(
        &Endpoint::Unix(l.path.clone()),
        Some(Duration::from_secs(20)),
    )
    .unwrap();
    let s = status_when(&mut c, |s| {
        s["controller"]["state"] == "engaged" && s["body"]["valid"] == true
    });
    assert_eq!(s["navigator"]["active"], false, "{s}");
    assert_eq!(s["navigator"]["stopped"], Value::Null, "never ran: {s}");
    // Across the body: the navigator sidewinds (with anti-compliant sidewinding).
    let heading = s["body"]["heading_rad"].as_f64().unwrap() + 1.5;
    let text = snakectl(&l, &["--take-over", "navigate", &format!("{heading}")]);
    assert!(text.contains("navigating towards"), "{text}");
    let s = status_when(&mut c, |s| {
        s["navigator"]["choice"] == "sidewind"
            && s["gait"] == "sidewinding"
            && s["controller"]["preset"] == "ac_sfc_lead"
            && s["controller"]["state"] == "engaged"
    });
    assert_eq!(s["navigator"]["active"], true, "{s}");
    // The echo bus's scripted torques repeat, so it may already have backed off and
    // come back (why `stuck`, `backed_off`): it starts sidewinding because the body
    // lies across the way.
    assert_eq!(s["controller"]["preset"], "ac_sfc_lead", "{s}");
    let travel = s["navigator"]["travel_rad"].as_f64().unwrap();
    assert!((travel - snaked::num::wrap_pi(heading)).abs() < 1e-9, "{s}");
    // It aims the controller once it drives: the nominal heading is 90° left of travel.
    let g = c
        .call("controller.get", Some(json!({"gait": "sidewinding"})))
        .unwrap();
    assert_eq!(g["controller"]["preset"], "ac_sfc_lead", "{g}");
    let text = snakectl(&l, &["status"]);
    assert!(text.contains("navigate  towards"), "{text}");
    assert!(
        text.contains("sidewind (") || text.contains("back_off ("),
        "{text}"
    );
    // The operator's hold wins: navigation stops, saying why.
    c.call("hold", None).unwrap();
    let s = status_when(&mut c, |s| s["navigator"]["stopped"] == "operator");
    assert_eq!(s["navigator"]["active"], false, "{s}");
    assert_eq!(s["mode"], "hold", "{s}");
    // Held, it cannot start again.
    let r = call(&mut c, "navigate", json!({"heading_rad": 0.0}));
    assert_eq!(error_code(&r), code::REFUSED, "{r}");
    assert!(error_message(&r).contains("mode hold"), "{r}");
    // Armed again: on, then off by snakectl.
    c.call("arm", None).unwrap();
    status_when(&mut c, |s| s["mode"] == "running");
    c.call("navigate", Some(json!({"heading_rad": travel})))
        .unwrap();
    status_when(&mut c, |s| s["navigator"]["active"] == true);
    let text = snakectl(&l, &["navigate", "off"]);
    assert!(text.contains("navigation off"), "{text}");
    let s = status_when(&mut c, |s| s["navigator"]["stopped"] == "off");
    assert_eq!(s["navigator"]["active"], false, "{s}");
}
