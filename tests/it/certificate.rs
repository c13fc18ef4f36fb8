//! `axiscal report`: the certificate's HTML read back by a small table reader written here
//! (not the renderer's code), every expanded uncertainty against twice the sigma that
//! `calibration.json` reports, by two paths: the diagonal of its `model_covariance`, and the
//! per-section sigmas (`row_sigma`, `zero_offset_sigma`, `couplings[].sigma`, `tool.sigma`),
//! which the procedure propagates separately.

use crate::common::{altered_csv, axiscal, scale_fields, stderr};
use std::collections::BTreeMap;
use std::path::Path;

/// The rows of the table `id` of `html`: per row its cells, each as (text, `data-value`).
fn table(html: &str, id: &str) -> Vec<Vec<(String, Option<f64>)>> {
    let start = html
        .find(&format!("<table id=\"{id}\">"))
        .unwrap_or_else(|| panic!("no table {id}"));
    let body = &html[start..start + html[start..].find("</table>").expect("a closed table")];
    body.split("<tr>")
        .skip(1)
        .map(|row| {
            row.split("<td")
                .skip(1)
                .map(|cell| {
                    let (attrs, rest) = cell.split_once('>').expect("a cell");
                    let text = unescape(rest.split("</td>").next().unwrap_or(""));
                    let value = attrs
                        .split_once("data-value=\"")
                        .map(|(_, v)| v.split('"').next().unwrap().parse().expect("a number"));
                    (text, value)
                })
                .collect()
        })
        .filter(|cells: &Vec<_>| !cells.is_empty())
        .collect()
}

/// HTML's five escapes undone.
fn unescape(text: &str) -> String {
    text.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&#39;", "'")
        .replace("&amp;", "&")
}

/// The factor from the vector's unit of a parameter to the unit the certificate shows.
fn factor(unit: &str) -> f64 {
    match unit {
        "mm" | "mrad" => 1e3,
        "deg" => 180.0 / std::f64::consts::PI,
        "1" => 1.0,
        other => panic!("unit {other}"),
    }
}

/// Checks the certificate in `dir` against `calibration.json` at `cal`.
pub(crate) fn check_certificate(dir: &Path, cal: &Path) {
    let html = std::fs::read_to_string(dir.join("certificate.html")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(cal).unwrap()).unwrap();
    // Self-contained: no script, no external resource.
    assert!(!html.contains("<script") && !html.contains(" src=") && !html.contains("<link"));
    assert_eq!(
        html.matches("http").count(),
        html.matches("xmlns=\"http://www.w3.org/2000/svg\"").count()
    );
    let names: Vec<&str> = json["model_covariance"]["names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap())
        .collect();
    let c = &json["model_covariance"]["covariance"];
    let variance: BTreeMap<&str, f64> = names
        .iter()
        .enumerate()
        .map(|(i, n)| (*n, c[i][i].as_f64().unwrap()))
        .collect();
    let rows = table(&html, "parameters-table");
    let mut shown: BTreeMap<String, f64> = BTreeMap::new();
    for cells in &rows {
        let (name, unit) = (&cells[0].0, cells[1].0.as_str());
        let (u, expanded) = (cells[4].1.unwrap(), cells[5].1.unwrap());
        assert_eq!(expanded, 2.0 * u, "{name}: U = 2 u");
        let key = names
            .iter()
            .find(|n| n.starts_with(&format!("{name} [")) || **n == name.as_str())
            .unwrap_or_else(|| panic!("{name} is not in model_covariance"));
        let from_json = variance[key].max(0.0).sqrt() * factor(unit);
        assert!(
            (u - from_json).abs() <= 1e-12 * from_json.max(1e-300),
            "{name}: u {u} against sqrt(C_ii) {from_json}"
        );
        shown.insert(name.clone(), u);
    }
    assert_eq!(rows.len() + 12, names.len(), "every scalar parameter shown once");
    // The second path: the sections' own sigmas, propagated by the procedure separately, by
    // central differences over other perturbation sets (steps 1e-3 sigma). The two agree to
    // about 1e-5 relative (row 5's b, the worst here: 6.4e-6); 1e-4 is ten times that and
    // still below the 4 digits the certificate prints. A parameter the base rule fixes (row
    // 1's b) has a sigma of rounding in both (1e-10 to 1e-8 mm): below a nanometre or a
    // microradian both are zero.
    let close = |what: &str, a: f64, b: f64| {
        assert!(
            (a - b).abs() <= 1e-4 * a.abs().max(b.abs()) + 1e-6,
            "{what}: {a} against {b}"
        );
    };
    for (k, r) in json["row_sigma"].as_array().into_iter().flatten().enumerate() {
        close(
            &format!("row {} a", k + 1),
            shown[&format!("row {} a", k + 1)],
            r["a_mm"].as_f64().unwrap(),
        );
        close(
            &format!("row {} b", k + 1),
            shown[&format!("row {} b", k + 1)],
            r["b_mm"].as_f64().unwrap(),
        );
    }
    for z in json["zero_offset_sigma"].as_array().into_iter().flatten() {
        let joint = z["joint"].as_u64().unwrap();
        let sigma = z["sigma_rad"]
            .as_f64()
            .map_or_else(|| z["sigma_mm"].as_f64().unwrap(), |r| r * 1e3);
        close(
            &format!("joint {joint} zero offset"),
            shown[&format!("joint {joint} zero offset")],
            sigma,
        );
    }
    for coupling in json["couplings"].as_array().into_iter().flatten() {
        let (from, to) = (coupling["from"].as_u64().unwrap(), coupling["to"].as_u64().unwrap());
        for (name, sigma) in coupling["parameter_names"]
            .as_array()
            .unwrap()
            .iter()
            .zip(coupling["sigma"].as_array().unwrap())
        {
            let key = format!("coupling {from}->{to} {}", name.as_str().unwrap());
            let key = shown
                .keys()
                .find(|k| k.starts_with(&key))
                .unwrap_or_else(|| panic!("{key}"));
            let s = sigma.as_f64().unwrap();
            let scale = if key.ends_with("ratio") || !key.contains("sin") && !key.contains("cos") {
                1.0
            } else {
                1e3
            };
            close(key, shown[key], s * scale);
        }
    }
    if let Some(tool) = json["tool"]["sigma"].as_object() {
        let frames = table(&html, "frames-table");
        let u_row = frames
            .iter()
            .find(|r| r[0].0 == "tool" && r[1].0 == "u")
            .expect("the tool's u row");
        let expanded_row = frames
            .iter()
            .find(|r| r[0].0 == "tool" && r[1].0.starts_with("U"))
            .expect("the tool's U row");
        for (i, key) in ["x_mm", "y_mm", "z_mm", "rx_mrad", "ry_mrad", "rz_mrad"]
            .iter()
            .enumerate()
        {
            close(
                &format!("tool {key}"),
                u_row[2 + i].1.unwrap(),
                tool[*key].as_f64().unwrap(),
            );
            assert_eq!(
                expanded_row[2 + i].1.unwrap(),
                2.0 * u_row[2 + i].1.unwrap(),
                "tool {key}: U = 2 u"
            );
        }
    }
}

#[test]
fn the_certificate_of_a_simulated_campaign_states_every_uncertainty_as_calibration_json() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    crate::common::simulate_analytic(d, 20, 11, "c.csv");
    axiscal()
        .current_dir(d)
        .args(["calibrate", "c.csv", "--out", "cal"])
        .assert()
        .success();
    let report = |out: &str| {
        axiscal()
            .current_dir(d)
            .args(["report", "--calibration", "cal/calibration.json", "--data", "c.csv"])
            .args([
                "--held-out",
                "c.csv",
                "--instrument",
                "theodolites <simulated> & co",
                "--out",
                out,
            ])
            .assert()
            .success();
    };
    report("cert");
    check_certificate(&d.join("cert"), &d.join("cal/calibration.json"));
    let html = std::fs::read_to_string(d.join("cert/certificate.html")).unwrap();
    assert!(
        html.contains("theodolites &lt;simulated&gt; &amp; co"),
        "text is escaped"
    );
    let held = table(&html, "held-out-table");
    let (before, after) = (held[0][1].1.unwrap(), held[1][1].1.unwrap());
    assert!(
        after < before,
        "calibration helps on held-out poses: {before} -> {after}"
    );
    assert_eq!(
        html.matches("class=\"residual-plot\"").count(),
        6,
        "one residual plot per joint"
    );
    // The same inputs, the same files.
    report("again");
    for f in ["certificate.html", "certificate.json"] {
        assert_eq!(
            std::fs::read(d.join("cert").join(f)).unwrap(),
            std::fs::read(d.join("again").join(f)).unwrap(),
            "{f}"
        );
    }
    // Without a model covariance: refused, naming the file and the key.
    let text = std::fs::read_to_string(d.join("cal/calibration.json")).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json.as_object_mut().unwrap().remove("model_covariance");
    std::fs::write(d.join("no-cov.json"), json.to_string()).unwrap();
    let out = axiscal()
        .current_dir(d)
        .args(["report", "--calibration", "no-cov.json", "--out", "c2"])
        .assert()
        .code(2);
    let err = stderr(&out);
    assert!(err.contains("no-cov.json") && err.contains("model_covariance"), "{err}");
}

/// A calibration from free poses (the independent generator's arm, `tests/data/independent-freepose`):
/// its certificate states every uncertainty as its `model_covariance` does, and warns that the
/// held-out poses given are its own.
#[test]
fn the_certificate_of_a_free_pose_calibration_warns_about_its_own_poses() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/independent-freepose");
    axiscal()
        .current_dir(d)
        .arg("calibrate")
        .arg(data.join("clean.csv"))
        .arg("--robot")
        .arg(data.join("kr-arm.toml"))
        .args(["--out", "cal"])
        .assert()
        .success();
    let out = axiscal()
        .current_dir(d)
        .args(["report", "--calibration", "cal/calibration.json", "--robot"])
        .arg(data.join("kr-arm.toml"))
        .arg("--held-out")
        .arg(data.join("clean.csv"))
        .args(["--out", "cert"])
        .assert()
        .success();
    assert!(stderr(&out).contains("fitted to free poses"), "{}", stderr(&out));
    check_certificate(&d.join("cert"), &d.join("cal/calibration.json"));
    // `--data` must be the free poses the calibration was made from: its own file is, the
    // same file without its last ten poses is not (the count names both).
    let report_data = |file: &Path, out: &str| {
        axiscal()
            .current_dir(d)
            .args(["report", "--calibration", "cal/calibration.json", "--robot"])
            .arg(data.join("kr-arm.toml"))
            .arg("--data")
            .arg(file)
            .args(["--out", out])
            .assert()
    };
    report_data(&data.join("clean.csv"), "own").success();
    std::fs::copy(data.join("clean.csv"), d.join("clean.csv")).unwrap();
    let fewer = crate::common::altered_csv(
        &d.join("clean.csv"),
        "fewer.csv",
        |f| f[2].parse::<usize>().is_ok_and(|step| step < 290),
        |_| {},
    );
    let e = stderr(&report_data(&fewer, "other").code(2));
    assert!(
        e.contains("fewer.csv: not the data") && e.contains("the data hold 290 free poses"),
        "{e}"
    );
    assert!(!d.join("other").exists());
}

/// The certificate of a simulated campaign's calibration: with its own data and held-out
/// poses it has no warning; held-out points in twice the scale are missed far beyond the
/// calibration's prediction and said (stderr and `warnings`); held-out commands in radians
/// are refused as a unit slip naming the file; `--data` without the axis-3 sweep is refused
/// naming the experiment (`--allow-other-data` summarises it, with a warning).
#[test]
fn held_out_data_in_other_units_and_data_that_are_not_the_calibrations_are_said() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    crate::common::simulate_analytic(d, 20, 12, "c.csv");
    axiscal()
        .current_dir(d)
        .args(["calibrate", "c.csv", "--out", "cal"])
        .assert()
        .success();
    let report = |data: &str, held_out: &str, out: &str, extra: &[&str]| {
        axiscal()
            .current_dir(d)
            .args(["report", "--calibration", "cal/calibration.json", "--data", data])
            .args(["--held-out", held_out, "--out", out])
            .args(extra)
            .output()
            .unwrap()
    };
    let json = |out: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(d.join(out).join("certificate.json")).unwrap()).unwrap()
    };
    let clean = report("c.csv", "c.csv", "clean", &[]);
    assert!(clean.status.success() && !String::from_utf8_lossy(&clean.stderr).contains("warning"));
    assert_eq!(json("clean")["warnings"], serde_json::json!([]));
    assert_eq!(json("clean")["held_out"]["beyond_prediction"], false);

    let csv = d.join("c.csv");
    altered_csv(&csv, "x2.csv", |_| true, |f| scale_fields(f, 4..7, 2.0));
    let out = report("c.csv", "x2.csv", "x2", &[]);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("warning: held-out poses of x2.csv: the calibrated model misses them by"),
        "{err}"
    );
    let cert = json("x2");
    assert_eq!(cert["held_out"]["beyond_prediction"], true);
    assert!(
        cert["warnings"][0]
            .as_str()
            .unwrap()
            .contains("check the held-out file's units"),
        "{cert}"
    );

    altered_csv(
        &csv,
        "rad.csv",
        |_| true,
        |f| {
            if f[1] == "0" && f[0] != "tool" {
                scale_fields(f, 7..13, 1f64.to_radians());
            }
        },
    );
    let out = report("c.csv", "rad.csv", "rad", &[]);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("rad.csv") && err.contains("cmd_1,") && err.contains("radians"),
        "{err}"
    );

    altered_csv(&csv, "noaxis3.csv", |f| f[0] != "axis3", |_| {});
    let out = report("noaxis3.csv", "c.csv", "noaxis3", &[]);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("noaxis3.csv: not the data cal/calibration.json was made from")
            && err.contains("joint 3 to experiment `axis3`")
            && err.contains("--allow-other-data"),
        "{err}"
    );
    let out = report("noaxis3.csv", "c.csv", "other", &["--allow-other-data"]);
    assert!(out.status.success());
    assert!(
        json("other")["warnings"]
            .to_string()
            .contains("not the ones the calibration records")
    );

    // A calibration edited by hand (joint 2's transmission negated): the certificate says so
    // in its warnings and its page, and stderr once.
    let text = std::fs::read_to_string(d.join("cal/calibration.json")).unwrap();
    let mut edited: serde_json::Value = serde_json::from_str(&text).unwrap();
    for key in ["sin", "cos"] {
        let c = &mut edited["robot"]["joints"][1]["transmission"][key][0];
        *c = serde_json::json!(-c.as_f64().unwrap());
    }
    std::fs::write(d.join("cal/edited.json"), edited.to_string()).unwrap();
    let out = axiscal()
        .current_dir(d)
        .args(["report", "--calibration", "cal/edited.json", "--out", "edited"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{err}");
    assert_eq!(
        err.matches("was edited after `axiscal calibrate` wrote it").count(),
        1,
        "{err}"
    );
    assert!(
        json("edited")["warnings"].to_string().contains("was edited after"),
        "{}",
        json("edited")
    );
    let page = std::fs::read_to_string(d.join("edited/certificate.html")).unwrap();
    assert!(page.contains("was edited after"));
}
