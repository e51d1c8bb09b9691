//! Recordings from ROS: `sensor_msgs/msg/JointState` messages in an MCAP file (rosbag2's default
//! storage since ROS 2 Iron, also written by Foxglove and `PyPI` `mcap`) become the recording CSV of
//! `../shared/spec/gap-recording.md` (`time`, `<joint>.q`, `<joint>.effort`) and are then read by
//! the CSV reader, so the two inputs follow one set of rules.
//!
//! Each `JointState` message is one row: time from its header stamp (the message's log time when the
//! stamp is zero), positions as `<name>.q`, efforts as `<name>.effort`; a joint a message does not
//! name is a missing sample. Messages are CDR (`message_encoding` `cdr`, schema `ros2msg`,
//! little- or big-endian). Chunks compressed with zstd or lz4 are read.
//!
//! Errors name the file, the topic and the message index (0-based, in log-time order).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use super::error::GapError;

/// The ROS 2 type name of the messages read.
pub const JOINT_STATE: &str = "sensor_msgs/msg/JointState";

/// One decoded `JointState`.
#[derive(Clone, Debug, PartialEq)]
pub struct JointState {
    /// Header stamp, seconds (0 when unset).
    pub stamp_s: f64,
    pub name: Vec<String>,
    pub position: Vec<f64>,
    pub velocity: Vec<f64>,
    pub effort: Vec<f64>,
}

/// A little CDR reader (OMG XCDR1 as ROS 2 writes it: a 4-byte encapsulation header, then
/// primitives aligned to their size relative to the end of that header).
struct Cdr<'a> {
    data: &'a [u8],
    at: usize,
    little: bool,
}

impl<'a> Cdr<'a> {
    fn new(data: &'a [u8]) -> Result<Self, String> {
        if data.len() < 4 {
            return Err(format!("{} bytes: shorter than the 4-byte CDR encapsulation header", data.len()));
        }
        let little = match data[1] {
            0x00 | 0x02 => false,
            0x01 | 0x03 => true,
            kind => return Err(format!("encapsulation kind {kind:#04x}: expected plain CDR (0x00 or 0x01)")),
        };
        Ok(Self { data: &data[4..], at: 0, little })
    }

    fn take(&mut self, n: usize, align: usize) -> Result<&'a [u8], String> {
        self.at = self.at.div_ceil(align) * align;
        let end = self.at.checked_add(n).filter(|&e| e <= self.data.len()).ok_or_else(|| format!("truncated at byte {}", self.at + 4))?;
        let bytes = &self.data[self.at..end];
        self.at = end;
        Ok(bytes)
    }

    fn u32(&mut self) -> Result<u32, String> {
        let b: [u8; 4] = self.take(4, 4)?.try_into().map_err(|_| "truncated".to_owned())?;
        Ok(if self.little { u32::from_le_bytes(b) } else { u32::from_be_bytes(b) })
    }

    fn i32(&mut self) -> Result<i32, String> {
        self.u32().map(|v| v as i32)
    }

    fn f64(&mut self) -> Result<f64, String> {
        let b: [u8; 8] = self.take(8, 8)?.try_into().map_err(|_| "truncated".to_owned())?;
        Ok(if self.little { f64::from_le_bytes(b) } else { f64::from_be_bytes(b) })
    }

    /// A sequence length, bounded by the bytes left (each element takes at least `min_size`).
    fn len(&mut self, min_size: usize) -> Result<usize, String> {
        let n = self.u32()? as usize;
        if n.saturating_mul(min_size) > self.data.len().saturating_sub(self.at) {
            return Err(format!("a sequence of {n} elements in a message of {} bytes", self.data.len() + 4));
        }
        Ok(n)
    }

    fn string(&mut self) -> Result<String, String> {
        let n = self.len(1)?;
        let bytes = self.take(n, 1)?;
        let text = bytes.strip_suffix(&[0]).unwrap_or(bytes);
        String::from_utf8(text.to_vec()).map_err(|e| format!("a string that is not UTF-8: {e}"))
    }

    fn f64s(&mut self) -> Result<Vec<f64>, String> {
        let n = self.len(8)?;
        (0..n).map(|_| self.f64()).collect()
    }
}

/// Decodes a CDR-encoded `sensor_msgs/msg/JointState`.
pub fn decode_joint_state(data: &[u8]) -> Result<JointState, String> {
    let mut r = Cdr::new(data)?;
    let sec = r.i32()?;
    let nanosec = r.u32()?;
    let _frame_id = r.string()?;
    let n = r.len(4)?;
    let name = (0..n).map(|_| r.string()).collect::<Result<Vec<_>, _>>()?;
    let position = r.f64s()?;
    let velocity = r.f64s()?;
    let effort = r.f64s()?;
    for (field, values) in [("position", &position), ("velocity", &velocity), ("effort", &effort)] {
        if !values.is_empty() && values.len() != name.len() {
            return Err(format!("{} {field} values for {} names; expected one per name or none", values.len(), name.len()));
        }
    }
    Ok(JointState { stamp_s: f64::from(sec) + f64::from(nanosec) * 1e-9, name, position, velocity, effort })
}

/// The `JointState` topics of an MCAP file, sorted.
pub fn joint_state_topics(bytes: &[u8], file: &Path) -> Result<Vec<String>, GapError> {
    let mut topics = std::collections::BTreeSet::new();
    for (index, message) in ::mcap::MessageStream::new(bytes).map_err(|e| mcap_error(file, "", None, &e.to_string()))?.enumerate() {
        let message = message.map_err(|e| mcap_error(file, "", Some(index), &e.to_string()))?;
        if message.channel.schema.as_ref().is_some_and(|s| s.name == JOINT_STATE) {
            topics.insert(message.channel.topic.clone());
        }
    }
    Ok(topics.into_iter().collect())
}

fn mcap_error(file: &Path, topic: &str, index: Option<usize>, message: &str) -> GapError {
    GapError::Mcap { file: file.to_path_buf(), topic: topic.to_owned(), index, message: message.to_owned() }
}

/// The recording CSV of the `JointState` messages on `topic` (the only `JointState` topic when
/// `None`).
pub fn mcap_to_csv(bytes: &[u8], file: &Path, topic: Option<&str>) -> Result<String, GapError> {
    let topics = joint_state_topics(bytes, file)?;
    let topic = match (topic, topics.as_slice()) {
        (Some(t), _) if topics.iter().any(|x| x == t) => t.to_owned(),
        (Some(t), _) => {
            return Err(mcap_error(
                file,
                t,
                None,
                &format!("no {JOINT_STATE} messages on this topic; the file has them on: {}", list(&topics)),
            ));
        }
        (None, [only]) => only.clone(),
        (None, []) => return Err(mcap_error(file, "", None, &format!("no {JOINT_STATE} messages in the file"))),
        (None, many) => {
            return Err(mcap_error(file, "", None, &format!("{} JointState topics ({}): choose one with --topic", many.len(), list(many))));
        }
    };
    let mut rows: Vec<(f64, JointState)> = Vec::new();
    let stream = ::mcap::MessageStream::new(bytes).map_err(|e| mcap_error(file, &topic, None, &e.to_string()))?;
    let mut index = 0;
    for message in stream {
        let message = message.map_err(|e| mcap_error(file, &topic, Some(index), &e.to_string()))?;
        if message.channel.topic != topic {
            continue;
        }
        if message.channel.message_encoding != "cdr" {
            return Err(mcap_error(
                file,
                &topic,
                Some(index),
                &format!("message encoding {:?}: expected \"cdr\"", message.channel.message_encoding),
            ));
        }
        let state = decode_joint_state(&message.data).map_err(|e| mcap_error(file, &topic, Some(index), &e))?;
        let t = if state.stamp_s > 0.0 { state.stamp_s } else { message.log_time as f64 * 1e-9 };
        rows.push((t, state));
        index += 1;
    }
    Ok(csv_of(&rows))
}

fn list(topics: &[String]) -> String {
    if topics.is_empty() { "none".to_owned() } else { topics.join(", ") }
}

/// The CSV text: times relative to the first message, a column per joint and quantity seen.
fn csv_of(rows: &[(f64, JointState)]) -> String {
    let t0 = rows.first().map_or(0.0, |(t, _)| *t);
    let mut q_joints = std::collections::BTreeSet::new();
    let mut effort_joints = std::collections::BTreeSet::new();
    for (_, s) in rows {
        for (k, n) in s.name.iter().enumerate() {
            if k < s.position.len() {
                q_joints.insert(n.clone());
            }
            if k < s.effort.len() {
                effort_joints.insert(n.clone());
            }
        }
    }
    let mut out = String::from("# description: converted from MCAP sensor_msgs/msg/JointState\ntime");
    for j in &q_joints {
        let _ = write!(out, ",{j}.q");
    }
    for j in &effort_joints {
        let _ = write!(out, ",{j}.effort");
    }
    out.push('\n');
    for (t, s) in rows {
        let at: BTreeMap<&str, usize> = s.name.iter().enumerate().map(|(k, n)| (n.as_str(), k)).collect();
        let _ = write!(out, "{}", t - t0);
        for j in &q_joints {
            out.push(',');
            if let Some(v) = at.get(j.as_str()).and_then(|&k| s.position.get(k)) {
                let _ = write!(out, "{v}");
            }
        }
        for j in &effort_joints {
            out.push(',');
            if let Some(v) = at.get(j.as_str()).and_then(|&k| s.effort.get(k)) {
                let _ = write!(out, "{v}");
            }
        }
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// CDR of a `JointState` (little-endian).
    pub(crate) fn joint_state_cdr(sec: i32, nanosec: u32, names: &[&str], position: &[f64], effort: &[f64]) -> Vec<u8> {
        let mut b = vec![0x00, 0x01, 0x00, 0x00];
        let mut body: Vec<u8> = Vec::new();
        let align = |body: &mut Vec<u8>, n: usize| {
            while !body.len().is_multiple_of(n) {
                body.push(0);
            }
        };
        let put_string = |body: &mut Vec<u8>, s: &str| {
            while !body.len().is_multiple_of(4) {
                body.push(0);
            }
            body.extend_from_slice(&((s.len() + 1) as u32).to_le_bytes());
            body.extend_from_slice(s.as_bytes());
            body.push(0);
        };
        body.extend_from_slice(&sec.to_le_bytes());
        body.extend_from_slice(&nanosec.to_le_bytes());
        put_string(&mut body, "base");
        align(&mut body, 4);
        body.extend_from_slice(&(names.len() as u32).to_le_bytes());
        for n in names {
            put_string(&mut body, n);
        }
        for values in [position, &[], effort] {
            align(&mut body, 4);
            body.extend_from_slice(&(values.len() as u32).to_le_bytes());
            for v in values {
                align(&mut body, 8);
                body.extend_from_slice(&v.to_le_bytes());
            }
        }
        b.extend_from_slice(&body);
        b
    }

    fn mcap_file(messages: &[(u64, Vec<u8>)], topic: &str) -> Vec<u8> {
        let mut out = std::io::Cursor::new(Vec::new());
        {
            let mut w = ::mcap::Writer::new(&mut out).expect("writer");
            let schema = w
                .add_schema(
                    JOINT_STATE,
                    "ros2msg",
                    b"std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort",
                )
                .expect("schema");
            let channel = w.add_channel(schema, topic, "cdr", &BTreeMap::new()).expect("channel");
            for (k, (log_time, data)) in messages.iter().enumerate() {
                let header = ::mcap::records::MessageHeader {
                    channel_id: channel,
                    sequence: k as u32,
                    log_time: *log_time,
                    publish_time: *log_time,
                };
                w.write_to_known_channel(&header, data).expect("message");
            }
            w.finish().expect("finish");
        }
        out.into_inner()
    }

    #[test]
    fn joint_states_become_the_recording_csv_with_dropouts() {
        let messages = vec![
            (1_000_000_000, joint_state_cdr(10, 0, &["hinge", "slide"], &[0.1, 0.2], &[1.5, 0.0])),
            (1_010_000_000, joint_state_cdr(10, 10_000_000, &["hinge"], &[0.11], &[1.4])),
            (1_020_000_000, joint_state_cdr(10, 20_000_000, &["slide", "hinge"], &[0.25, 0.12], &[])),
        ];
        let bytes = mcap_file(&messages, "/joint_states");
        let csv = mcap_to_csv(&bytes, Path::new("run.mcap"), None).expect("converted");
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines[1], "time,hinge.q,slide.q,hinge.effort,slide.effort");
        assert_eq!(lines[2], "0,0.1,0.2,1.5,0");
        assert!(lines[3].starts_with("0.00999") && lines[3].ends_with(",0.11,,1.4,"), "{}", lines[3]);
        assert!(lines[4].ends_with(",0.12,0.25,,"), "{}", lines[4]);
        let rec = super::super::parse_recording(&csv, Path::new("run.mcap")).expect("the CSV reader takes it");
        assert_eq!(rec.time_s.len(), 3);
    }

    #[test]
    fn malformed_mcap_gets_a_named_error() {
        let check = |bytes: &[u8], topic: Option<&str>, expected: &str| {
            let err = mcap_to_csv(bytes, Path::new("run.mcap"), topic).expect_err("malformed").to_string();
            assert!(err.contains(expected), "{err:?} should contain {expected:?}");
        };
        check(b"not an mcap file", None, "run.mcap");
        let good = mcap_file(&[(1, joint_state_cdr(0, 1, &["a"], &[0.0], &[]))], "/js");
        check(&good, Some("/other"), "topic /other: no sensor_msgs/msg/JointState messages on this topic; the file has them on: /js");
        let mut truncated = joint_state_cdr(0, 1, &["a", "b"], &[0.0, 1.0], &[]);
        truncated.truncate(truncated.len() - 5);
        let bad = mcap_file(&[(1, joint_state_cdr(0, 1, &["a"], &[0.0], &[])), (2, truncated)], "/js");
        check(&bad, None, "topic /js, message 1: truncated");
        let lying = {
            let mut m = joint_state_cdr(0, 1, &["a"], &[0.0], &[]);
            // The name count claims a billion names.
            m[4 + 8 + 4 + 5 + 3..4 + 8 + 4 + 5 + 3 + 4].copy_from_slice(&1_000_000_000_u32.to_le_bytes());
            m
        };
        check(&mcap_file(&[(1, lying)], "/js"), None, "a sequence of 1000000000 elements");
    }
}
