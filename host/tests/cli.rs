//! The `et` binary from the outside: what a user or a script sees.

use std::process::Command;

fn et(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_et"))
        .args(args)
        .output()
        .expect("run et")
}

#[test]
fn protocol_json_reports_k_and_p_for_every_l() {
    for l in (4..=32).step_by(2) {
        for name in ["adjacent", "pseudo-polar", "pp-pp", "opposite"] {
            let out = et(&[
                "protocol",
                "--electrodes",
                &l.to_string(),
                "--protocol",
                name,
                "--json",
            ]);
            if name == "opposite" && l == 4 {
                // K = L (L - 4) = 0: refused with a reason, not an empty table.
                assert!(!out.status.success());
                assert!(String::from_utf8_lossy(&out.stderr).contains("no usable measurement"));
                continue;
            }
            assert!(
                out.status.success(),
                "{name} L={l}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("valid JSON");
            let k = v["K"].as_u64().unwrap() as usize;
            let rows = v["injections"].as_array().unwrap();
            assert_eq!(rows.len(), l);
            let measured: usize = rows
                .iter()
                .map(|r| r["measurements"].as_array().unwrap().len())
                .sum();
            assert_eq!(measured, k, "{name} L={l}");
            // No measurement touches the row's current-carrying electrodes.
            for r in rows {
                let (src, sink) = (r["source"].as_u64().unwrap(), r["sink"].as_u64().unwrap());
                for m in r["measurements"].as_array().unwrap() {
                    let (a, b) = (m[0].as_u64().unwrap(), m[1].as_u64().unwrap());
                    assert!(![src, sink].contains(&a) && ![src, sink].contains(&b));
                }
            }
            if name == "opposite" {
                assert_eq!(v["p_halved"].as_u64().unwrap() as usize, l * (l - 4) / 2);
            }
        }
    }
}

#[test]
fn protocol_text_and_errors_teach() {
    let out = et(&["protocol", "-l", "16", "-p", "ad"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("K = 208"), "{text}");
    let bad = et(&["protocol", "-l", "7"]);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("even number from 4 to 32"));
    let unknown = et(&["protocol", "-p", "spiral"]);
    assert!(
        String::from_utf8_lossy(&unknown.stderr)
            .contains("use adjacent, pseudo-polar, pp-pp or opposite")
    );
    let general = et(&[
        "protocol",
        "-l",
        "16",
        "--drive-skip",
        "6",
        "--measure-skip",
        "0",
        "--measure-skip",
        "6",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_slice(&general.stdout).unwrap();
    assert_eq!(v["K"], 400, "the general form with PP-PP's skips is PP-PP");
    let help = et(&["protocol", "--help"]);
    assert!(String::from_utf8_lossy(&help.stdout).contains("Examples:"));
}
