//! Interaction recordings (spec `gap-recording.md` §2): CSV with `# key: value` metadata lines,
//! one header row, a strictly increasing `time` column, joint positions, efforts and (checked,
//! unused) velocities, tracked link poses; empty and `nan` cells are dropouts. Every rejection names the file, line, column and field.
//!
//! Before the header, blank lines are skipped and every line starting with `#` must be
//! `# key: value` (spec §2; the value may itself hold colons, unknown keys are kept). A `#` line
//! without `key:` is rejected (line, column 1): the spec describes no free comments, and skipping
//! it would silently drop a mistyped `# gravity 0 0 -9.81`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::error::GapError;

/// What a recording column measures.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Channel {
    /// `time`, seconds.
    Time,
    /// `<joint>.q`: joint position (rad or m).
    JointPosition(String),
    /// `<joint>.effort`: applied generalized effort (N·m or N).
    JointEffort(String),
    /// `<joint>.velocity`: measured joint velocity (rad/s or m/s), as robot logs and ROS
    /// `JointState` carry it beside the position. Read and checked, not used: velocities and
    /// accelerations come from the positions, through the same filter as every term and the
    /// efforts (parallel filtering); a velocity measured by other means (a drive's own
    /// differentiation, its own filter and delay) would put the two sides out of step.
    JointVelocity(String),
    /// `<link>.pos.<axis>`: world position of the link frame, axis 0..3 = x, y, z.
    LinkPosition(String, usize),
    /// `<link>.quat.<c>`: world orientation of the link, component 0..4 = w, x, y, z.
    LinkQuaternion(String, usize),
}

/// A tracked link's samples (NaN = dropout).
#[derive(Debug, Clone, Default)]
pub struct LinkTrack {
    /// World position x, y, z of the link frame origin, metres.
    pub position_m: Option<[Vec<f64>; 3]>,
    /// World orientation w, x, y, z.
    pub quaternion: Option<[Vec<f64>; 4]>,
}

/// A parsed recording. Missing samples are `f64::NAN`.
#[derive(Debug, Clone)]
pub struct Recording {
    /// Where it was read from (for messages).
    pub file: PathBuf,
    /// All metadata lines, including unknown keys.
    pub metadata: BTreeMap<String, String>,
    /// Gravity in the world frame, m/s² (`# gravity:`, default 0 0 -9.81).
    pub gravity_mps2: [f64; 3],
    /// Sample times, seconds, strictly increasing.
    pub time_s: Vec<f64>,
    /// Measured joint positions by joint name.
    pub joint_q: BTreeMap<String, Vec<f64>>,
    /// Applied efforts by joint name (dropouts already held from the previous sample, 0 before the first).
    pub joint_effort: BTreeMap<String, Vec<f64>>,
    /// Tracked link poses by link name.
    pub links: BTreeMap<String, LinkTrack>,
    /// 1-based line of the header row.
    pub header_line: usize,
    /// The header cells in order, with what each measures.
    pub columns: Vec<(String, Channel)>,
}

fn csv_error(file: &Path, line: usize, column: usize, field: &str, expected: &str, found: &str) -> GapError {
    GapError::Csv {
        file: file.to_path_buf(),
        line,
        column,
        field: field.to_owned(),
        expected: expected.to_owned(),
        found: found.to_owned(),
    }
}

fn bytecount_newlines(bytes: &[u8]) -> usize {
    bytes.split(|&b| b == b'\n').count() - 1
}

/// Builds a channel from the column's stem.
type Make = fn(String) -> Channel;

fn channel_of(name: &str) -> Option<Channel> {
    if name == "time" {
        return Some(Channel::Time);
    }
    let suffixes: [(&str, Make); 10] = [
        (".q", Channel::JointPosition),
        (".effort", Channel::JointEffort),
        (".velocity", Channel::JointVelocity),
        (".pos.x", |n| Channel::LinkPosition(n, 0)),
        (".pos.y", |n| Channel::LinkPosition(n, 1)),
        (".pos.z", |n| Channel::LinkPosition(n, 2)),
        (".quat.w", |n| Channel::LinkQuaternion(n, 0)),
        (".quat.x", |n| Channel::LinkQuaternion(n, 1)),
        (".quat.y", |n| Channel::LinkQuaternion(n, 2)),
        (".quat.z", |n| Channel::LinkQuaternion(n, 3)),
    ];
    suffixes.iter().find_map(|(suffix, make)| {
        let stem = name.strip_suffix(suffix)?;
        (!stem.is_empty()).then(|| make(stem.to_owned()))
    })
}

/// Reads a recording from disk.
pub fn read_recording(path: &Path) -> Result<Recording, GapError> {
    let bytes = crate::io::read_bytes(path)?;
    let text = String::from_utf8(bytes).map_err(|e| {
        let upto = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = bytecount_newlines(upto) + 1;
        csv_error(path, line, 1, "encoding", "UTF-8 text", "invalid UTF-8 bytes")
    })?;
    parse_recording(&text, path)
}

/// Parses recording text; `file` is used in messages only.
pub fn parse_recording(text: &str, file: &Path) -> Result<Recording, GapError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut metadata = BTreeMap::new();
    let mut header: Option<(usize, Vec<(String, Channel)>)> = None;
    let mut rows: Vec<(usize, Vec<&str>)> = Vec::new();
    for (index, raw) in text.lines().enumerate() {
        let line_no = index + 1;
        let line = raw.trim_end_matches('\r');
        if line.trim().is_empty() {
            continue;
        }
        if header.is_none() {
            if let Some(rest) = line.trim_start().strip_prefix('#') {
                let Some((key, value)) = rest.split_once(':') else {
                    return Err(csv_error(file, line_no, 1, "metadata", "`# key: value`", line));
                };
                let key = key.trim();
                if key.is_empty() {
                    return Err(csv_error(file, line_no, 1, "metadata", "a key before `:`", line));
                }
                metadata.insert(key.to_owned(), value.trim().to_owned());
                continue;
            }
            let mut columns: Vec<(String, Channel)> = Vec::new();
            for (c, cell) in line.split(',').enumerate() {
                let name = cell.trim();
                let Some(channel) = channel_of(name) else {
                    return Err(csv_error(
                        file,
                        line_no,
                        c + 1,
                        "header",
                        "`time`, `<joint>.q`, `<joint>.effort`, `<joint>.velocity`, `<link>.pos.x|y|z` or `<link>.quat.w|x|y|z`",
                        name,
                    ));
                };
                if columns.iter().any(|(n, _)| n == name) {
                    return Err(csv_error(file, line_no, c + 1, "header", "each column once", name));
                }
                columns.push((name.to_owned(), channel));
            }
            if !columns.iter().any(|(_, ch)| *ch == Channel::Time) {
                return Err(csv_error(file, line_no, 1, "header", "a `time` column", line));
            }
            header = Some((line_no, columns));
            continue;
        }
        rows.push((line_no, line.split(',').collect()));
    }
    let Some((header_line, columns)) = header else {
        return Err(csv_error(file, text.lines().count().max(1), 1, "header", "a header row", "end of file"));
    };
    check_pose_groups(file, header_line, &columns)?;

    let gravity_mps2 = match metadata.get("gravity") {
        None => [0.0, 0.0, -9.81],
        Some(value) => {
            let parts: Vec<&str> = value.split(|c: char| c.is_whitespace() || c == ',').filter(|s| !s.is_empty()).collect();
            let numbers: Vec<f64> = parts.iter().filter_map(|s| s.parse::<f64>().ok()).filter(|v| v.is_finite()).collect();
            if parts.len() != 3 || numbers.len() != 3 {
                let line = text.lines().position(|l| l.trim_start().starts_with('#') && l.contains("gravity")).map_or(1, |i| i + 1);
                return Err(csv_error(file, line, 1, "gravity", "three finite numbers (m/s^2)", value));
            }
            [numbers[0], numbers[1], numbers[2]]
        }
    };

    let n = rows.len();
    let mut data: Vec<Vec<f64>> = vec![Vec::with_capacity(n); columns.len()];
    for (line_no, cells) in &rows {
        if cells.len() != columns.len() {
            return Err(csv_error(
                file,
                *line_no,
                cells.len().min(columns.len()) + 1,
                "row",
                &format!("{} cells like the header", columns.len()),
                &format!("{} cells", cells.len()),
            ));
        }
        for (c, cell) in cells.iter().enumerate() {
            let cell = cell.trim();
            let (name, channel) = &columns[c];
            let value = if cell.is_empty() {
                if *channel == Channel::Time {
                    return Err(csv_error(file, *line_no, c + 1, name, "a time in seconds", cell));
                }
                f64::NAN
            } else {
                match cell.parse::<f64>() {
                    Ok(v) if v.is_finite() => v,
                    // `nan` (numpy's `savetxt`, many loggers) is a missing sample, as an empty cell is.
                    Ok(v) if v.is_nan() && *channel != Channel::Time => f64::NAN,
                    _ => return Err(csv_error(file, *line_no, c + 1, name, "a finite number, `nan` or an empty cell", cell)),
                }
            };
            if *channel == Channel::Time
                && let Some(&previous) = data[c].last()
                && value <= previous
            {
                return Err(csv_error(file, *line_no, c + 1, name, &format!("a time after {previous} (strictly increasing)"), cell));
            }
            data[c].push(value);
        }
    }
    let mut recording = Recording {
        file: file.to_path_buf(),
        metadata,
        gravity_mps2,
        time_s: Vec::new(),
        joint_q: BTreeMap::new(),
        joint_effort: BTreeMap::new(),
        links: BTreeMap::new(),
        header_line,
        columns: columns.clone(),
    };
    for ((_, channel), values) in columns.into_iter().zip(data) {
        match channel {
            Channel::Time => recording.time_s = values,
            Channel::JointPosition(j) => {
                recording.joint_q.insert(j, values);
            }
            Channel::JointEffort(j) => {
                let mut held = 0.0;
                let values = values
                    .into_iter()
                    .map(|v| {
                        if v.is_finite() {
                            held = v;
                        }
                        held
                    })
                    .collect();
                recording.joint_effort.insert(j, values);
            }
            // Checked above (finite or empty), not used: see `Channel::JointVelocity`.
            Channel::JointVelocity(_) => {}
            Channel::LinkPosition(l, axis) => {
                let track = recording.links.entry(l).or_default();
                track.position_m.get_or_insert_with(|| [Vec::new(), Vec::new(), Vec::new()])[axis] = values;
            }
            Channel::LinkQuaternion(l, comp) => {
                let track = recording.links.entry(l).or_default();
                track.quaternion.get_or_insert_with(|| [Vec::new(), Vec::new(), Vec::new(), Vec::new()])[comp] = values;
            }
        }
    }
    Ok(recording)
}

/// A link with `pos.x` must have `pos.y` and `pos.z` too; likewise all four quaternion components.
fn check_pose_groups(file: &Path, header_line: usize, columns: &[(String, Channel)]) -> Result<(), GapError> {
    for (c, (name, channel)) in columns.iter().enumerate() {
        let (link, wanted): (&str, Vec<String>) = match channel {
            Channel::LinkPosition(l, _) => (l, ["x", "y", "z"].iter().map(|a| format!("{l}.pos.{a}")).collect()),
            Channel::LinkQuaternion(l, _) => (l, ["w", "x", "y", "z"].iter().map(|a| format!("{l}.quat.{a}")).collect()),
            _ => continue,
        };
        if let Some(missing) = wanted.iter().find(|w| !columns.iter().any(|(n, _)| n == *w)) {
            return Err(csv_error(file, header_line, c + 1, name, &format!("also a `{missing}` column for link {link}"), name));
        }
    }
    Ok(())
}

impl Recording {
    /// The model the recording names in its `# model:` line (relative to the CSV file), if any.
    #[must_use]
    pub fn named_model_path(&self) -> Option<PathBuf> {
        let rel = self.metadata.get("model")?;
        Some(self.file.parent().unwrap_or(std::path::Path::new(".")).join(rel.trim()))
    }

    /// Checks every column against the model: joint columns must name a movable joint, pose
    /// columns a link. The error points at the header cell.
    pub fn check_names(&self, joint_names: &[&str], link_names: &[&str]) -> Result<(), GapError> {
        for (c, (name, channel)) in self.columns.iter().enumerate() {
            let (ok, what) = match channel {
                Channel::Time => continue,
                Channel::JointPosition(j) | Channel::JointEffort(j) | Channel::JointVelocity(j) => {
                    (joint_names.contains(&j.as_str()), "a movable joint of the model")
                }
                Channel::LinkPosition(l, _) | Channel::LinkQuaternion(l, _) => (link_names.contains(&l.as_str()), "a link of the model"),
            };
            if !ok {
                return Err(csv_error(&self.file, self.header_line, c + 1, name, what, name));
            }
        }
        Ok(())
    }

    /// The effort applied to `joint` at sample `i` (zero without an effort column).
    #[must_use]
    pub fn effort(&self, joint: &str, i: usize) -> f64 {
        self.joint_effort.get(joint).and_then(|v| v.get(i)).copied().unwrap_or(0.0)
    }

    /// The recording read at every `step`-th sample (the first, then every `step`-th after it):
    /// positions and poses as measured at those samples; each effort, which holds until the next
    /// sample (spec §2), averaged over the holds its sample now stands for, weighed by their
    /// durations, so that the impulse it applies until the next sample kept is the one the
    /// recording applied (the last sample's hold taken as the median step).
    #[must_use]
    pub fn every(&self, step: usize) -> Self {
        let step = step.max(1);
        let n = self.time_s.len();
        let kept: Vec<usize> = (0..n).step_by(step).collect();
        let pick = |v: &Vec<f64>| kept.iter().map(|&i| v[i]).collect::<Vec<f64>>();
        let mut steps: Vec<f64> = self.time_s.windows(2).map(|w| w[1] - w[0]).collect();
        steps.sort_by(f64::total_cmp);
        let last_hold = steps.get(steps.len() / 2).copied().unwrap_or(0.0);
        let hold = |i: usize| if i + 1 < n { self.time_s[i + 1] - self.time_s[i] } else { last_hold };
        let average = |v: &Vec<f64>| -> Vec<f64> {
            kept.iter()
                .map(|&a| {
                    let b = (a + step).min(n);
                    let (impulse, duration) = (a..b).fold((0.0, 0.0), |(s, d), i| (s + v[i] * hold(i), d + hold(i)));
                    if duration > 0.0 { impulse / duration } else { v[a] }
                })
                .collect()
        };
        let links = self
            .links
            .iter()
            .map(|(name, track)| {
                let position_m = track.position_m.as_ref().map(|p| [pick(&p[0]), pick(&p[1]), pick(&p[2])]);
                let quaternion = track.quaternion.as_ref().map(|q| [pick(&q[0]), pick(&q[1]), pick(&q[2]), pick(&q[3])]);
                (name.clone(), LinkTrack { position_m, quaternion })
            })
            .collect();
        Self {
            file: self.file.clone(),
            metadata: self.metadata.clone(),
            gravity_mps2: self.gravity_mps2,
            time_s: pick(&self.time_s),
            joint_q: self.joint_q.iter().map(|(j, q)| (j.clone(), pick(q))).collect(),
            joint_effort: self.joint_effort.iter().map(|(j, e)| (j.clone(), average(e))).collect(),
            links,
            header_line: self.header_line,
            columns: self.columns.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_log_read_at_every_third_sample_keeps_each_efforts_impulse() {
        let text = "time,arm.q,arm.effort\n0,0,1\n0.001,0.1,2\n0.003,0.2,3\n0.004,0.3,4\n0.005,0.4,5\n";
        let r = parse_recording(text, Path::new("fast.csv")).expect("parses").every(3);
        assert_eq!(r.time_s, vec![0.0, 0.004]);
        assert_eq!(r.joint_q["arm"], vec![0.0, 0.3]);
        // Holds of 1, 2 and 1 ms: (1·1 + 2·2 + 3·1) / 4; then 1 ms each, the last the median step.
        let e = &r.joint_effort["arm"];
        assert!((e[0] - 2.0).abs() < 1e-12 && (e[1] - 4.5).abs() < 1e-12, "{e:?}");
    }

    #[test]
    fn reads_metadata_dropouts_and_columns_in_any_order() {
        let text =
            "# description: door test\n# gravity: 0 0 -9.8\n# extra: kept\nhinge.q,time,hinge.effort\n0.1,0,1\n,0.01,\n0.12,0.03,2\n";
        let r = parse_recording(text, Path::new("r.csv")).expect("parses");
        assert_eq!(r.time_s, vec![0.0, 0.01, 0.03]);
        assert!(r.joint_q["hinge"][1].is_nan());
        assert_eq!(r.joint_effort["hinge"], vec![1.0, 1.0, 2.0]);
        assert!((r.gravity_mps2[2] + 9.8).abs() < 1e-12 && r.gravity_mps2[0] == 0.0);
        assert_eq!(r.metadata["extra"], "kept");
        assert_eq!(r.header_line, 4);
    }

    #[test]
    fn a_robot_log_with_measured_velocities_is_read_and_its_velocities_checked() {
        // Regression: a CSV written from ROS `JointState` (position, velocity, effort) was refused
        // at its `.velocity` header cell.
        let text = "time,arm.q,arm.velocity,arm.effort\n0,0.1,0.0,1\n0.01,0.11,1.0,1\n";
        let r = parse_recording(text, Path::new("log.csv")).expect("parses");
        assert_eq!(r.joint_q["arm"], vec![0.1, 0.11]);
        assert!(r.check_names(&["arm"], &[]).is_ok());
        let e = r.check_names(&["elbow"], &[]).expect_err("no joint arm");
        assert!(matches!(e, GapError::Csv { line: 1, column: 2, .. }), "{e}");
        let e = parse_recording("time,arm.q,arm.velocity\n0,0.1,fast\n", Path::new("log.csv")).expect_err("not a number");
        assert!(matches!(e, GapError::Csv { line: 2, column: 3, .. }), "{e}");
    }

    #[test]
    fn nan_written_by_a_logger_is_a_missing_sample_but_not_in_time_and_inf_is_refused() {
        let r = parse_recording("time,arm.q,arm.effort\n0,0.1,NaN\n0.01,nan,1\n", Path::new("log.csv")).expect("parses");
        assert!(r.joint_q["arm"][1].is_nan());
        assert_eq!(r.joint_effort["arm"], vec![0.0, 1.0], "a missing effort holds the one before (none yet: 0)");
        let e = parse_recording("time,arm.q\nnan,0.1\n", Path::new("log.csv")).expect_err("time must be a number");
        assert!(matches!(e, GapError::Csv { line: 2, column: 1, .. }), "{e}");
        let e = parse_recording("time,arm.q\n0,inf\n", Path::new("log.csv")).expect_err("not finite");
        assert!(matches!(e, GapError::Csv { line: 2, column: 2, .. }), "{e}");
    }

    #[test]
    fn pose_groups_must_be_complete() {
        let e = parse_recording("time,door.pos.x,door.pos.y\n0,1,2\n", Path::new("p.csv")).expect_err("incomplete");
        assert!(matches!(e, GapError::Csv { line: 1, column: 2, .. }), "{e}");
    }
}
