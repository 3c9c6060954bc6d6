//! Which dataset each recording belongs to: the name the user gave it, or else the folder it
//! lies in, split by sensor size where that folder mixes sensors, so that loose recordings
//! of different cameras are never averaged as one dataset without saying so.

/// Where a recording's dataset name comes from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Origin {
    /// Named by the user (kept even when it mixes sensors; the report warns of that).
    Named(String),
    /// The folder the recording lies in, or the folder of recordings that was given.
    Folder(String),
}

/// The dataset name of each recording, given its origin and its sensor (`WxH`): a user's
/// name as given; a folder's name where all its recordings share one sensor, else
/// `FOLDER (WxH)`, one dataset per sensor size.
pub fn dataset_names(recordings: &[(Origin, String)]) -> Vec<String> {
    let mixes = |folder: &str| {
        let mut sensors = recordings
            .iter()
            .filter_map(|(origin, sensor)| match origin {
                Origin::Folder(f) if f == folder => Some(sensor),
                _ => None,
            });
        let first = sensors.next();
        sensors.any(|s| Some(s) != first)
    };
    recordings
        .iter()
        .map(|(origin, sensor)| match origin {
            Origin::Named(name) => name.clone(),
            Origin::Folder(folder) if mixes(folder) => format!("{folder} ({sensor})"),
            Origin::Folder(folder) => folder.clone(),
        })
        .collect()
}

/// A name usable as one file or folder name: ASCII letters, digits, `-` and `_`, every other
/// run of characters one `_`, none at the ends (`real (346x260)` -> `real_346x260`).
pub fn file_stem(name: &str) -> String {
    let mut out = String::with_capacity(name.len());
    for c in name.chars() {
        if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
            out.push(c);
        } else if !out.ends_with('_') {
            out.push('_');
        }
    }
    let trimmed = out.trim_matches('_');
    if trimmed.is_empty() {
        "dataset".to_string()
    } else {
        trimmed.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn folder(name: &str, sensor: &str) -> (Origin, String) {
        (Origin::Folder(name.into()), sensor.into())
    }

    #[test]
    fn a_folder_of_mixed_sensors_splits_by_sensor_and_named_datasets_stay_whole() {
        let names = dataset_names(&[
            folder("real", "346x260"),
            folder("real", "640x480"),
            folder("real", "346x260"),
            folder("ijrr", "240x180"),
            (Origin::Named("mine".into()), "346x260".into()),
            (Origin::Named("mine".into()), "640x480".into()),
        ]);
        assert_eq!(
            names,
            [
                "real (346x260)",
                "real (640x480)",
                "real (346x260)",
                "ijrr",
                "mine",
                "mine"
            ]
        );
    }

    #[test]
    fn file_stems_are_safe() {
        assert_eq!(file_stem("real (346x260)"), "real_346x260");
        assert_eq!(file_stem("on_screen"), "on_screen");
        assert_eq!(file_stem("../.."), "dataset");
    }
}
