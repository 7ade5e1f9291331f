//! `--light-points` on the command line: recorded where the harness keys cells, rendered as
//! asked, refused when unknown.
use std::process::{Command, Output};

fn manylights(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_manylights"))
        .args(args)
        .output()
        .expect("binary runs")
}

fn json(o: &Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).expect("JSON")
}

#[test]
fn light_points_are_recorded_and_keyed() {
    let resolved = |extra: &[&str]| {
        let mut args = vec!["strategy", "--json", "--strategy", "power+bsdf"];
        args.extend_from_slice(extra);
        json(&manylights(&args))
    };
    // `area`, the default, leaves the key as it was before the flag existed.
    let default = resolved(&[]);
    assert!(default.get("light_points").is_none(), "{default}");
    assert_eq!(resolved(&["--light-points", "area"]), default);
    let solid = resolved(&["--light-points", "solid-angle"]);
    assert_eq!(solid["light_points"], "solid-angle");
    let warp = resolved(&["--light-points", "solid-angle-warp"]);
    assert_ne!(solid, warp);

    let dir = std::env::temp_dir().join(format!("manylights-light-points-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("r.exr");
    let o = manylights(&[
        "render",
        "builtin:cornell",
        "--light-points",
        "solid-angle-warp",
        "--spp",
        "1",
        "--width",
        "8",
        "--height",
        "8",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("r.json")).unwrap()).unwrap();
    assert_eq!(meta["light_points"], "solid-angle-warp");
    assert_eq!(
        meta["resolved_strategy"]["light_points"],
        "solid-angle-warp"
    );
    let _ = std::fs::remove_dir_all(&dir);

    let bad = manylights(&["strategy", "--json", "--light-points", "cone"]);
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        err.contains("solid-angle") && !err.contains("panicked"),
        "{err}"
    );
}
