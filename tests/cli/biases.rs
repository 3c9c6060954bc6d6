//! Sensor biases in and beside recordings: `info`, `stats --json` and `estimate` show them
//! exactly as saved (none of the shared recordings carries any).

use super::common::*;

#[test]
fn the_shared_recordings_carry_no_biases() {
    for name in [
        "evk4_faery_evt3.raw",
        "evk4_faery_gen4.dat",
        "gen3_faery_evt2.raw",
        "gen3_expelliarmus_evt2.raw",
        "davis346_faery.aedat4",
        "dvxplorer_tonic.aedat4",
    ] {
        let info = json(&["info", real(name).to_str().unwrap()]);
        assert!(info.get("biases").is_none(), "{name}: {info}");
    }
}

/// A copy of the Gen3 RAW with `% bias` lines added to its header.
fn raw_with_header_biases(dir: &std::path::Path) -> std::path::PathBuf {
    let original = std::fs::read(real("gen3_faery_evt2.raw")).unwrap();
    let mut with = b"% bias bias_diff_on 374\n% bias_diff_off 222\n".to_vec();
    with.extend_from_slice(&original);
    let path = dir.join("gen3.raw");
    std::fs::write(&path, with).unwrap();
    path
}

#[test]
fn header_bias_lines_and_bias_files_are_shown_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let raw = raw_with_header_biases(dir.path());
    let info = json(&["info", raw.to_str().unwrap()]);
    assert_eq!(info["biases"]["values"]["bias_diff_on"], 374, "{info}");
    assert_eq!(info["biases"]["values"]["bias_diff_off"], 222);
    assert_eq!(
        info["events"], 521_252,
        "the bias lines do not change the events"
    );
    // a bias file beside the RAW wins over the header
    std::fs::write(
        dir.path().join("gen3.bias"),
        "% Gen3 biases\n299   % bias_diff\n 228 % bias_diff_off\n370 % bias_diff_on\n",
    )
    .unwrap();
    let stats = json(&["stats", raw.to_str().unwrap()]);
    let b = &stats["biases"];
    assert_eq!(b["values"]["bias_diff"], 299, "{b}");
    assert_eq!(b["values"]["bias_diff_off"], 228);
    assert_eq!(b["values"]["bias_diff_on"], 370);
    assert!(b["source"].as_str().unwrap().ends_with("gen3.bias"));
    let estimate = json(&["estimate", "eppps", raw.to_str().unwrap()]);
    assert_eq!(estimate["biases"]["values"]["bias_diff_on"], 370);
}
