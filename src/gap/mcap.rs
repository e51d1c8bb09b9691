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

/// The ROS 2 type name of transform messages (`/tf`, `/tf_static`).
pub const TF_MESSAGE: &str = "tf2_msgs/msg/TFMessage";

/// One `geometry_msgs/msg/TransformStamped`: `child` in `parent`'s frame.
#[derive(Clone, Debug, PartialEq)]
pub struct StampedTransform {
    /// Header stamp, seconds (0 when unset).
    pub stamp_s: f64,
    pub parent: String,
    pub child: String,
    pub translation: [f64; 3],
    /// x, y, z, w.
    pub rotation_xyzw: [f64; 4],
}

/// Decodes a CDR-encoded `tf2_msgs/msg/TFMessage`.
pub fn decode_tf_message(data: &[u8]) -> Result<Vec<StampedTransform>, String> {
    let mut r = Cdr::new(data)?;
    // Each TransformStamped takes at least 4 + 4 + 4 + 4 + 7 × 8 bytes.
    let n = r.len(72)?;
    (0..n)
        .map(|_| {
            let sec = r.i32()?;
            let nanosec = r.u32()?;
            let parent = r.string()?;
            let child = r.string()?;
            let translation = [r.f64()?, r.f64()?, r.f64()?];
            let rotation_xyzw = [r.f64()?, r.f64()?, r.f64()?, r.f64()?];
            Ok(StampedTransform { stamp_s: f64::from(sec) + f64::from(nanosec) * 1e-9, parent, child, translation, rotation_xyzw })
        })
        .collect()
}

/// Which TF frames become tracked link poses: the model's links moved by a joint, expressed in
/// its root link's frame (the root is fixed to the world at the identity, spec §1).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TfFrames {
    /// The model's root link.
    pub root: String,
    /// Links whose world pose is written as `<link>.pos.*` / `<link>.quat.*`.
    pub tracked: std::collections::BTreeSet<String>,
}

impl TfFrames {
    /// The links of `model` that a movable joint moves, and its root.
    #[must_use]
    pub fn of_model(model: &super::GapModel) -> Self {
        let tracked =
            model.joints.iter().filter(|j| j.kind != super::model::DofKind::Fixed).map(|j| model.links[j.child].name.clone()).collect();
        Self { root: model.links.get(model.root).map(|l| l.name.clone()).unwrap_or_default(), tracked }
    }
}

/// One input of [`ros_to_csv`]: a file's name (for errors) and bytes.
pub type McapSource<'a> = (&'a Path, &'a [u8]);

/// The recording CSV of an MCAP file: see [`ros_to_csv`].
pub fn mcap_to_csv(bytes: &[u8], file: &Path, topic: Option<&str>, tf: Option<&TfFrames>) -> Result<String, GapError> {
    ros_to_csv(&[(file, bytes)], topic, tf)
}

/// The recording CSV of one or more MCAP files (a rosbag2's): the `JointState` messages on `topic`
/// (the only `JointState` topic when `None`) as `<joint>.q` / `<joint>.effort`, and, with `tf`,
/// every `TFMessage` (`/tf`, `/tf_static`) turned into the world poses of the tracked links (the
/// latest transform of every TF edge composed up to the model's root link when TF has it, else up
/// to the top of the link's TF tree, taken as the world), a row at each `/tf` message. Rows at the
/// same stamp are merged. An error names the file, the topic and the message index.
pub fn ros_to_csv(sources: &[McapSource<'_>], topic: Option<&str>, tf: Option<&TfFrames>) -> Result<String, GapError> {
    let mut messages = Vec::new();
    for (file, bytes) in sources {
        messages.extend(read_messages(bytes, file)?.into_iter().map(|m| (*file, m)));
    }
    let topics_of = |schema: &str| -> std::collections::BTreeSet<&str> {
        messages.iter().filter(|(_, m)| m.schema.as_deref() == Some(schema)).map(|(_, m)| m.topic.as_str()).collect()
    };
    let states: Vec<String> = topics_of(JOINT_STATE).into_iter().map(str::to_owned).collect();
    let tf_topics = topics_of(TF_MESSAGE);
    let poses_wanted = tf.is_some_and(|f| !f.tracked.is_empty()) && !tf_topics.is_empty();
    let file0 = sources.first().map_or(Path::new(""), |(f, _)| *f);
    let joint_topic = choose_joint_topic(file0, topic, &states, poses_wanted, tf.is_some())?;
    let mut rows = Rows::default();
    let mut edges = TfEdges::default();
    let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
    for (file, message) in &messages {
        let is_joint = joint_topic.as_deref() == Some(message.topic.as_str());
        let is_tf = poses_wanted && tf_topics.contains(message.topic.as_str());
        if !is_joint && !is_tf {
            continue;
        }
        let index = counts.entry(message.topic.as_str()).or_default();
        let at = *index;
        *index += 1;
        let bad = |m: &str| mcap_error(file, &message.topic, Some(at), m);
        if message.encoding != "cdr" {
            return Err(bad(&format!("message encoding {:?}: expected \"cdr\"", message.encoding)));
        }
        let log_time_s = message.log_time as f64 * 1e-9;
        if is_joint {
            let state = decode_joint_state(&message.data).map_err(|e| bad(&e))?;
            rows.joint_state(if state.stamp_s > 0.0 { state.stamp_s } else { log_time_s }, &state);
        } else if let Some(frames) = tf {
            let transforms = decode_tf_message(&message.data).map_err(|e| bad(&e))?;
            let stamp = transforms.iter().map(|t| t.stamp_s).find(|t| *t > 0.0).unwrap_or(log_time_s);
            edges.update(&transforms);
            if !message.topic.ends_with("tf_static") {
                rows.poses(stamp, &edges, frames);
            }
        }
    }
    Ok(rows.csv())
}

/// The `JointState` topic read: `topic` when the file has it, else the only one; `None` when
/// there is none but TF gives the poses wanted.
fn choose_joint_topic(
    file: &Path,
    topic: Option<&str>,
    states: &[String],
    poses_wanted: bool,
    with_tf: bool,
) -> Result<Option<String>, GapError> {
    match (topic, states) {
        (Some(t), _) if states.iter().any(|x| x == t) => Ok(Some(t.to_owned())),
        (Some(t), _) => {
            Err(mcap_error(file, t, None, &format!("no {JOINT_STATE} messages on this topic; the file has them on: {}", list(states))))
        }
        (None, [only]) => Ok(Some(only.clone())),
        (None, []) if poses_wanted => Ok(None),
        (None, []) => {
            let what = if with_tf {
                format!("no {JOINT_STATE} messages and no {TF_MESSAGE} of the model's links")
            } else {
                format!("no {JOINT_STATE} messages")
            };
            Err(mcap_error(file, "", None, &format!("{what} in the file")))
        }
        (None, many) => {
            Err(mcap_error(file, "", None, &format!("{} JointState topics ({}): choose one with --topic", many.len(), list(many))))
        }
    }
}

/// The largest record, or decompressed chunk, an MCAP file may hold here: `MCAP_EXPANSION` times
/// the file's size, within [1 MiB, 256 MiB]. A chunk header is free to claim any uncompressed size,
/// and the `mcap` crate's message stream allocates what it claims before checking (found by
/// fuzzing: a 4 KB file asked for more than 2 GB); `JointState` and TF chunks compress a few times
/// to some tens of times.
pub const MAX_MCAP_RECORD_BYTES: usize = 256 << 20;
/// See [`MAX_MCAP_RECORD_BYTES`].
const MCAP_EXPANSION: usize = 64;

/// The MCAP records this reader parses: schemas, channels, messages and the chunks holding them.
const READ_OPCODES: [u8; 4] =
    [::mcap::records::op::SCHEMA, ::mcap::records::op::CHANNEL, ::mcap::records::op::MESSAGE, ::mcap::records::op::CHUNK];

/// One message of an MCAP file, with its channel's topic, schema name and encoding.
struct RosMessage {
    topic: String,
    schema: Option<String>,
    encoding: String,
    log_time: u64,
    data: Vec<u8>,
}

/// Every message of an MCAP file in file order (chunks inflated here, [`inflate_chunk`]), records
/// no larger than [`MAX_MCAP_RECORD_BYTES`] allows.
fn read_messages(bytes: &[u8], file: &Path) -> Result<Vec<RosMessage>, GapError> {
    use ::mcap::records::Record;
    use ::mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
    let limit = bytes.len().saturating_mul(MCAP_EXPANSION).clamp(1 << 20, MAX_MCAP_RECORD_BYTES);
    // Chunks come out whole: the crate's own inflation can loop forever on a bad stream.
    let options = LinearReaderOptions::default().with_record_length_limit(limit).with_emit_chunks(true);
    let mut reader = LinearReader::new_with_options(options);
    let fail = |e: &dyn std::fmt::Display| mcap_error(file, "", None, &e.to_string());
    let mut rest = bytes;
    let mut state = McapContents::default();
    while let Some(event) = reader.next_event() {
        match event.map_err(|e| fail(&e))? {
            LinearReadEvent::ReadRequest(need) => {
                let n = need.min(rest.len());
                reader.insert(n).copy_from_slice(&rest[..n]);
                reader.notify_read(n);
                rest = &rest[n..];
            }
            // Only the records read are parsed: the crate's parser of others (attachments) can
            // panic on a short record (found by fuzzing).
            LinearReadEvent::Record { opcode, .. } if !READ_OPCODES.contains(&opcode) => {}
            LinearReadEvent::Record { data, opcode } => match ::mcap::parse_record(opcode, data).map_err(|e| fail(&e))? {
                Record::Chunk { header, data } => {
                    let inflated = inflate_chunk(&header.compression, &data, header.uncompressed_size, limit).map_err(|e| fail(&e))?;
                    for (op, body) in chunk_records(&inflated).map_err(|e| fail(&e))? {
                        if READ_OPCODES.contains(&op) {
                            state.take(::mcap::parse_record(op, body).map_err(|e| fail(&e))?).map_err(|e| fail(&e))?;
                        }
                    }
                }
                record => state.take(record).map_err(|e| fail(&e))?,
            },
        }
    }
    Ok(state.messages)
}

/// Schemas and channels seen so far, and the messages on them.
#[derive(Default)]
struct McapContents {
    schemas: BTreeMap<u16, String>,
    channels: BTreeMap<u16, (String, u16, String)>,
    messages: Vec<RosMessage>,
}

impl McapContents {
    fn take(&mut self, record: ::mcap::records::Record<'_>) -> Result<(), String> {
        use ::mcap::records::Record;
        match record {
            Record::Schema { header, .. } => {
                self.schemas.insert(header.id, header.name);
            }
            Record::Channel(c) => {
                self.channels.insert(c.id, (c.topic, c.schema_id, c.message_encoding));
            }
            Record::Message { header, data } => {
                let Some((topic, schema_id, encoding)) = self.channels.get(&header.channel_id) else {
                    return Err(format!("a message on channel {} that no channel record declares", header.channel_id));
                };
                self.messages.push(RosMessage {
                    topic: topic.clone(),
                    schema: self.schemas.get(schema_id).cloned(),
                    encoding: encoding.clone(),
                    log_time: header.log_time,
                    data: data.into_owned(),
                });
            }
            _ => {}
        }
        Ok(())
    }
}

/// A chunk's records, inflated: exactly `uncompressed_size` bytes (at most `limit`) or an error.
/// Written here rather than left to the `mcap` crate, whose streaming inflation spins forever
/// when a stream stops making progress before its declared size.
fn inflate_chunk(compression: &str, data: &[u8], uncompressed_size: u64, limit: usize) -> Result<Vec<u8>, String> {
    use std::io::Read as _;
    let size = usize::try_from(uncompressed_size)
        .ok()
        .filter(|&n| n <= limit)
        .ok_or_else(|| format!("a chunk declares {uncompressed_size} bytes uncompressed, more than the {limit} allowed for this file"))?;
    let out = match compression {
        "" => data.to_vec(),
        "zstd" => zstd::bulk::decompress(data, size).map_err(|e| format!("zstd chunk: {e}"))?,
        "lz4" => {
            let mut out = Vec::new();
            let decoder = lz4::Decoder::new(data).map_err(|e| format!("lz4 chunk: {e}"))?;
            // One byte past the declared size shows a chunk that holds more than it says.
            decoder.take(size as u64 + 1).read_to_end(&mut out).map_err(|e| format!("lz4 chunk: {e}"))?;
            out
        }
        other => return Err(format!("chunk compression {other:?}: expected none, zstd or lz4")),
    };
    if out.len() != size {
        return Err(format!("a chunk declares {size} bytes uncompressed and holds {}", out.len()));
    }
    Ok(out)
}

/// The records of an inflated chunk: opcode, then a little-endian u64 length, then the body.
fn chunk_records(bytes: &[u8]) -> Result<Vec<(u8, &[u8])>, String> {
    let mut out = Vec::new();
    let mut at = 0;
    while at < bytes.len() {
        let head = bytes.get(at..at + 9).ok_or_else(|| format!("a record header cut off at byte {at} of a chunk"))?;
        let len = u64::from_le_bytes(head[1..9].try_into().map_err(|_| "a record length".to_owned())?);
        let end = usize::try_from(len).ok().and_then(|n| (at + 9).checked_add(n)).filter(|&e| e <= bytes.len());
        let end = end.ok_or_else(|| format!("a record of {len} bytes at byte {at} of a chunk of {}", bytes.len()))?;
        out.push((head[0], &bytes[at + 9..end]));
        at = end;
    }
    Ok(out)
}

/// The recording CSV of a rosbag2 folder with MCAP storage: its `.mcap` files in name order
/// (`metadata.yaml`, when present, must say `storage_identifier: mcap`), as [`ros_to_csv`].
pub fn rosbag_to_csv(dir: &Path, topic: Option<&str>, tf: Option<&TfFrames>) -> Result<String, GapError> {
    let metadata = dir.join("metadata.yaml");
    if metadata.is_file() {
        let text = String::from_utf8_lossy(&crate::io::read_bytes(&metadata)?).into_owned();
        let storage = text.lines().find_map(|l| l.trim().strip_prefix("storage_identifier:")).map(|v| v.trim().trim_matches(['"', '\'']));
        if let Some(storage) = storage.filter(|s| *s != "mcap") {
            return Err(mcap_error(
                &metadata,
                "",
                None,
                &format!("rosbag2 storage {storage:?}: only MCAP is read (convert with `ros2 bag convert`)"),
            ));
        }
    }
    let entries = std::fs::read_dir(dir).map_err(|e| crate::io::IoError::new(dir, "list", e))?;
    let mut files: Vec<std::path::PathBuf> = entries
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("mcap")))
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(mcap_error(dir, "", None, "a rosbag2 folder without .mcap files"));
    }
    let bytes: Vec<Vec<u8>> = files.iter().map(|f| crate::io::read_bytes(f)).collect::<Result<_, _>>()?;
    let sources: Vec<McapSource<'_>> = files.iter().map(std::path::PathBuf::as_path).zip(bytes.iter().map(Vec::as_slice)).collect();
    ros_to_csv(&sources, topic, tf)
}

fn mcap_error(file: &Path, topic: &str, index: Option<usize>, message: &str) -> GapError {
    GapError::Mcap { file: file.to_path_buf(), topic: topic.to_owned(), index, message: message.to_owned() }
}

fn list(topics: &[String]) -> String {
    if topics.is_empty() { "none".to_owned() } else { topics.join(", ") }
}

/// A CSV column, in the order written: positions, efforts, then link poses.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Column {
    Q(String),
    Effort(String),
    /// Link, component 0..3 = x, y, z.
    Position(String, usize),
    /// Link, component 0..4 = w, x, y, z.
    Quaternion(String, usize),
}

impl Column {
    fn name(&self) -> String {
        match self {
            Self::Q(j) => format!("{j}.q"),
            Self::Effort(j) => format!("{j}.effort"),
            Self::Position(l, c) => format!("{l}.pos.{}", ["x", "y", "z"][*c]),
            Self::Quaternion(l, c) => format!("{l}.quat.{}", ["w", "x", "y", "z"][*c]),
        }
    }
}

/// Rows by stamp (ns, so that equal stamps merge).
#[derive(Default)]
struct Rows(BTreeMap<i64, BTreeMap<Column, f64>>);

impl Rows {
    fn at(&mut self, t_s: f64) -> &mut BTreeMap<Column, f64> {
        self.0.entry((t_s * 1e9).round() as i64).or_default()
    }

    fn joint_state(&mut self, t_s: f64, s: &JointState) {
        let row = self.at(t_s);
        for (k, n) in s.name.iter().enumerate() {
            if let Some(&v) = s.position.get(k) {
                row.insert(Column::Q(n.clone()), v);
            }
            if let Some(&v) = s.effort.get(k) {
                row.insert(Column::Effort(n.clone()), v);
            }
        }
    }

    fn poses(&mut self, t_s: f64, edges: &TfEdges, frames: &TfFrames) {
        let poses: Vec<(&String, glam::DVec3, glam::DQuat)> =
            frames.tracked.iter().filter_map(|l| edges.world_pose(l, &frames.root).map(|(p, q)| (l, p, q))).collect();
        if poses.is_empty() {
            return;
        }
        let row = self.at(t_s);
        for (link, p, q) in poses {
            for (c, v) in p.to_array().into_iter().enumerate() {
                row.insert(Column::Position(link.clone(), c), v);
            }
            for (c, v) in [q.w, q.x, q.y, q.z].into_iter().enumerate() {
                row.insert(Column::Quaternion(link.clone(), c), v);
            }
        }
    }

    /// The CSV text: times relative to the first row, a column per quantity seen.
    fn csv(&self) -> String {
        let columns: std::collections::BTreeSet<&Column> = self.0.values().flat_map(BTreeMap::keys).collect();
        let mut out =
            String::from("# description: converted from ROS messages (MCAP: sensor_msgs/msg/JointState, tf2_msgs/msg/TFMessage)\ntime");
        for c in &columns {
            let _ = write!(out, ",{}", c.name());
        }
        out.push('\n');
        let t0 = self.0.keys().next().copied().unwrap_or(0);
        for (t, row) in &self.0 {
            let _ = write!(out, "{}", (t - t0) as f64 * 1e-9);
            for c in &columns {
                out.push(',');
                if let Some(v) = row.get(*c) {
                    let _ = write!(out, "{v}");
                }
            }
            out.push('\n');
        }
        out
    }
}

/// The latest transform of every TF edge, by child frame.
#[derive(Default)]
struct TfEdges(BTreeMap<String, (String, glam::DVec3, glam::DQuat)>);

impl TfEdges {
    fn update(&mut self, transforms: &[StampedTransform]) {
        for t in transforms {
            let [x, y, z, w] = t.rotation_xyzw;
            let q = glam::DQuat::from_xyzw(x, y, z, w);
            // A zero or non-finite quaternion is no rotation anyone meant: the edge is skipped.
            if !(q.is_finite() && q.length() > 1e-6 && t.translation.iter().all(|v| v.is_finite())) {
                continue;
            }
            self.0.insert(t.child.clone(), (t.parent.clone(), glam::DVec3::from_array(t.translation), q.normalize()));
        }
    }

    /// `frame`'s pose in the top frame of its TF tree, and that top frame.
    fn in_top(&self, frame: &str) -> (String, glam::DVec3, glam::DQuat) {
        let (mut p, mut q) = (glam::DVec3::ZERO, glam::DQuat::IDENTITY);
        let mut at = frame.to_owned();
        // Bounded by the number of edges: a TF cycle (malformed) stops there.
        for _ in 0..=self.0.len() {
            let Some((parent, t, r)) = self.0.get(&at) else { break };
            p = *t + *r * p;
            q = *r * q;
            at.clone_from(parent);
        }
        (at, p, q)
    }

    /// `link`'s pose in the frame of `root` when the two share a TF tree, else in the top frame of
    /// its own tree; `None` when TF has not given `link` yet.
    fn world_pose(&self, link: &str, root: &str) -> Option<(glam::DVec3, glam::DQuat)> {
        if !self.0.contains_key(link) {
            return None;
        }
        let (top, p, q) = self.in_top(link);
        let (root_top, rp, rq) = self.in_top(root);
        if root_top == top && root != top {
            let inv = rq.inverse();
            return Some((inv * (p - rp), inv * q));
        }
        Some((p, q))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A little-endian CDR writer (the reader's counterpart, for test messages).
    struct CdrOut(Vec<u8>);

    impl CdrOut {
        fn new() -> Self {
            Self(Vec::new())
        }
        fn align(&mut self, n: usize) {
            while !self.0.len().is_multiple_of(n) {
                self.0.push(0);
            }
        }
        fn u32(&mut self, v: u32) {
            self.align(4);
            self.0.extend_from_slice(&v.to_le_bytes());
        }
        fn f64(&mut self, v: f64) {
            self.align(8);
            self.0.extend_from_slice(&v.to_le_bytes());
        }
        fn string(&mut self, s: &str) {
            self.u32((s.len() + 1) as u32);
            self.0.extend_from_slice(s.as_bytes());
            self.0.push(0);
        }
        fn stamp(&mut self, sec: i32, nanosec: u32) {
            self.u32(sec as u32);
            self.u32(nanosec);
        }
        /// The message: the encapsulation header (CDR, little-endian), then the body.
        fn finish(self) -> Vec<u8> {
            let mut b = vec![0x00, 0x01, 0x00, 0x00];
            b.extend_from_slice(&self.0);
            b
        }
    }

    /// CDR of a `JointState` (little-endian).
    pub(crate) fn joint_state_cdr(sec: i32, nanosec: u32, names: &[&str], position: &[f64], effort: &[f64]) -> Vec<u8> {
        let mut c = CdrOut::new();
        c.stamp(sec, nanosec);
        c.string("base");
        c.u32(names.len() as u32);
        for n in names {
            c.string(n);
        }
        for values in [position, &[], effort] {
            c.u32(values.len() as u32);
            for v in values {
                c.f64(*v);
            }
        }
        c.finish()
    }

    /// CDR of a `TFMessage` (little-endian): (parent, child, translation, rotation xyzw) at one stamp.
    fn tf_cdr(sec: i32, nanosec: u32, transforms: &[(&str, &str, [f64; 3], [f64; 4])]) -> Vec<u8> {
        let mut c = CdrOut::new();
        c.u32(transforms.len() as u32);
        for (parent, child, t, r) in transforms {
            c.stamp(sec, nanosec);
            c.string(parent);
            c.string(child);
            for v in t.iter().chain(r) {
                c.f64(*v);
            }
        }
        c.finish()
    }

    /// An MCAP of messages on several topics: (topic, schema, log time, CDR).
    fn mcap_of(messages: &[(&str, &str, u64, Vec<u8>)]) -> Vec<u8> {
        let mut out = std::io::Cursor::new(Vec::new());
        {
            let mut w = ::mcap::Writer::new(&mut out).expect("writer");
            let mut channels = BTreeMap::new();
            for (k, (topic, schema, log_time, data)) in messages.iter().enumerate() {
                let channel = if let Some(c) = channels.get(topic) {
                    *c
                } else {
                    let s = w.add_schema(schema, "ros2msg", b"").expect("schema");
                    let c = w.add_channel(s, topic, "cdr", &BTreeMap::new()).expect("channel");
                    channels.insert(*topic, c);
                    c
                };
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

    /// An MCAP of `JointState` messages on one topic: (log time, CDR).
    fn mcap_file(messages: &[(u64, Vec<u8>)], topic: &str) -> Vec<u8> {
        let on_topic: Vec<(&str, &str, u64, Vec<u8>)> = messages.iter().map(|(t, d)| (topic, JOINT_STATE, *t, d.clone())).collect();
        mcap_of(&on_topic)
    }

    #[test]
    fn tf_becomes_tracked_link_poses_in_the_model_root_frame() {
        let half = std::f64::consts::FRAC_1_SQRT_2;
        // map → base (static, 1 m up, turned 90° about z); base → door (turning); a joint state at
        // the first stamp too.
        let messages = vec![
            ("/tf_static", TF_MESSAGE, 1, tf_cdr(10, 0, &[("map", "base", [0.0, 0.0, 1.0], [0.0, 0.0, half, half])])),
            ("/tf", TF_MESSAGE, 2, tf_cdr(10, 0, &[("base", "door", [0.5, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])])),
            ("/joint_states", JOINT_STATE, 3, joint_state_cdr(10, 0, &["hinge"], &[0.0], &[])),
            ("/tf", TF_MESSAGE, 4, tf_cdr(10, 10_000_000, &[("base", "door", [0.5, 0.0, 0.0], [0.0, 0.0, half, half])])),
        ];
        let bytes = mcap_of(&messages);
        let frames = TfFrames { root: "base".to_owned(), tracked: ["door".to_owned()].into() };
        let csv = mcap_to_csv(&bytes, Path::new("run.mcap"), None, Some(&frames)).expect("converted");
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines[1], "time,hinge.q,door.pos.x,door.pos.y,door.pos.z,door.quat.w,door.quat.x,door.quat.y,door.quat.z");
        // In the root's (base's) frame, not map's: the static turn and lift do not show.
        let first: Vec<f64> = lines[2].split(',').map(|v| v.parse().expect("number")).collect();
        let want = [0.0, 0.0, 0.5, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0];
        assert!(
            first.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-12),
            "the joint state and the pose at one stamp merge: {}",
            lines[2]
        );
        let last: Vec<&str> = lines[3].split(',').collect();
        let num = |k: usize| last[k].parse::<f64>().expect("number");
        assert!((num(0) - 0.01).abs() < 1e-9 && last[1].is_empty(), "no joint state at the second stamp: {}", lines[3]);
        assert!((num(5) - half).abs() < 1e-12 && (num(8) - half).abs() < 1e-12, "{}", lines[3]);
        // A root TF does not know: poses in the top frame of the link's tree.
        let elsewhere = TfFrames { root: "cabinet".to_owned(), tracked: ["door".to_owned()].into() };
        let csv = mcap_to_csv(&bytes, Path::new("run.mcap"), None, Some(&elsewhere)).expect("converted");
        let first: Vec<&str> = csv.lines().nth(2).expect("row").split(',').collect();
        let x: f64 = first[2].parse().expect("x");
        let y: f64 = first[3].parse().expect("y");
        let z: f64 = first[4].parse().expect("z");
        assert!(x.abs() < 1e-12 && (y - 0.5).abs() < 1e-12 && (z - 1.0).abs() < 1e-12, "{first:?}");
        let rec = super::super::parse_recording(&csv, Path::new("run.mcap")).expect("the CSV reader takes it");
        assert_eq!(rec.time_s.len(), 2);
        // A TF-only recording without a model's frames is refused, naming what is missing.
        let tf_only = mcap_of(&messages[..2]);
        let err = mcap_to_csv(&tf_only, Path::new("run.mcap"), None, None).expect_err("nothing to read").to_string();
        assert!(err.contains("no sensor_msgs/msg/JointState messages"), "{err}");
    }

    #[test]
    fn joint_states_become_the_recording_csv_with_dropouts() {
        let messages = vec![
            (1_000_000_000, joint_state_cdr(10, 0, &["hinge", "slide"], &[0.1, 0.2], &[1.5, 0.0])),
            (1_010_000_000, joint_state_cdr(10, 10_000_000, &["hinge"], &[0.11], &[1.4])),
            (1_020_000_000, joint_state_cdr(10, 20_000_000, &["slide", "hinge"], &[0.25, 0.12], &[])),
        ];
        let bytes = mcap_file(&messages, "/joint_states");
        let csv = mcap_to_csv(&bytes, Path::new("run.mcap"), None, None).expect("converted");
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines[1], "time,hinge.q,slide.q,hinge.effort,slide.effort");
        assert_eq!(lines[2], "0,0.1,0.2,1.5,0");
        assert_eq!(lines[3], "0.01,0.11,,1.4,", "times from the stamps, in whole nanoseconds");
        assert!(lines[4].ends_with(",0.12,0.25,,"), "{}", lines[4]);
        let rec = super::super::parse_recording(&csv, Path::new("run.mcap")).expect("the CSV reader takes it");
        assert_eq!(rec.time_s.len(), 3);
    }

    #[test]
    fn malformed_mcap_gets_a_named_error() {
        let check = |bytes: &[u8], topic: Option<&str>, expected: &str| {
            let err = mcap_to_csv(bytes, Path::new("run.mcap"), topic, None).expect_err("malformed").to_string();
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
