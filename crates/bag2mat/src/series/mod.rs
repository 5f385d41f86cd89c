//! The one read path: Imu topics of any input as columns, in record-time order — what
//! `bag2mat` converts and both analysers consume.
//!
//! On top of a [`Source`] (any container), written once for every format: the topic rules
//! (exact name, else the other slash form with a note; `--all-imu-topics`), the missing-topic
//! error that lists every topic with type and count, the type check, the progress bar, the
//! parallel decode of the parts (ROS 1 or CDR codec, straight into the columns), the stable
//! sort by record time (as `rosbag::View` and rosbag2's reader deliver messages), and the
//! accounting of what the container promised against what was delivered ([`TopicReport`]).

use rayon::prelude::*;

use crate::error::{Error, TopicSummary};
use crate::imu_msg::{self, ImuSample};
use crate::shared::note::Note;
use crate::source::{self, Channel, Encoding, InputKind, Loss, Source};
use crate::time::RosTime;

mod losses;
mod selection;

use crate::imu_msg::MIN_IMU_PAYLOAD;
use crate::rows::{Rows, RowsMut};
use losses::{LossTally, loss_notes, part_losses, skipped_topics};
use selection::{Selected, select};

/// How to read.
#[derive(Debug, Clone, Copy, Default)]
pub struct ReadOptions {
    /// No progress bar.
    pub quiet: bool,
}

/// Which topics to read. None named and not `all_imu` (the default): `preferred` when the
/// input has it, else the input's only `sensor_msgs/Imu` topic, an error naming them when
/// there are several.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct TopicSelector {
    /// Topics by name (each tried in the other slash form when missing).
    pub topics: Vec<String>,
    /// Every topic that carries `sensor_msgs/Imu`, besides the named ones.
    pub all_imu: bool,
    /// The topic read when none is named and the input has it (in either slash form): the
    /// analysers' upstream default `imu`. `None` (bag2mat): only the only-topic rule.
    pub preferred: Option<String>,
}

impl TopicSelector {
    /// One named topic.
    pub fn one(topic: &str) -> TopicSelector {
        TopicSelector {
            topics: vec![topic.to_string()],
            ..TopicSelector::default()
        }
    }
}

/// Which time goes into the time column (also the tools' `--time` values).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum TimeColumn {
    /// The container's record (receive, log) time: bagconvert's rule.
    #[default]
    Record,
    /// `header.stamp`: the sensor's time, as imu_utils uses it.
    Header,
}

impl TimeColumn {
    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            TimeColumn::Record => "record",
            TimeColumn::Header => "header",
        }
    }
}

/// What the container promised for one topic and what was delivered.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TopicReport {
    /// Messages the index, summary or metadata promises; `None` when it keeps no count.
    pub promised: Option<u64>,
    /// Messages delivered as rows.
    pub delivered: u64,
    /// Messages found but not decodable as Imu (or not decompressible), skipped.
    pub undecodable: u64,
    /// Why the first undecodable message failed.
    pub first_error: Option<String>,
    /// Parts that could not be read to their end, with what they held of this topic.
    pub losses: Vec<Loss>,
}

/// The Imu samples of one topic, in record-time order.
#[derive(Debug, Clone, Default)]
pub struct ImuSeries {
    /// The topic as it is named in the bag.
    pub topic: String,
    /// Its type as recorded (`sensor_msgs/Imu` or `sensor_msgs/msg/Imu`).
    pub msg_type: String,
    /// Record (receive) time of each message.
    pub record_time: Vec<RosTime>,
    /// `header.stamp` of each message.
    pub stamp: Vec<RosTime>,
    /// `header.seq` of each message (0 for ROS 2, which has none).
    pub seq: Vec<u32>,
    /// Linear acceleration, one column per axis x, y, z, m/s².
    pub acc: [Vec<f64>; 3],
    /// Angular velocity, one column per axis x, y, z, rad/s.
    pub gyro: [Vec<f64>; 3],
    /// Things the binary should tell the user on stderr (topic fallback, lost chunks, …).
    pub notes: Vec<Note>,
    /// Promised against delivered.
    pub report: TopicReport,
    /// Where each row was stored, when the rows were sorted by record time (`None`: row
    /// order is storage order); the record check finds a clock that steps back with it.
    pub storage_order: Option<Vec<u32>>,
    /// For a topic of integrated deltas (PX4 `vehicle_imu`), its rows' integration
    /// intervals: whether they are samples to analyse is [`ImuSeries::check_integration`]'s.
    pub integration: Option<crate::Integration>,
}

impl ImuSeries {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.record_time.len()
    }

    /// True when there are no samples.
    pub fn is_empty(&self) -> bool {
        self.record_time.is_empty()
    }

    /// Angular velocity `[x, y, z]` of sample `i`, rad/s.
    pub fn gyro_at(&self, i: usize) -> [f64; 3] {
        std::array::from_fn(|c| self.gyro[c][i])
    }

    /// Linear acceleration `[x, y, z]` of sample `i`, m/s².
    pub fn acc_at(&self, i: usize) -> [f64; 3] {
        std::array::from_fn(|c| self.acc[c][i])
    }

    /// The sensor this topic does not carry: its three columns NaN in every sample (PX4
    /// `sensor_gyro`/`sensor_accel`, ArduPilot batches, a text log with one sensor).
    pub fn absent_sensor(&self) -> Option<crate::Sensor> {
        let none = |c: &[Vec<f64>; 3]| !self.is_empty() && c.iter().flatten().all(|v| v.is_nan());
        if none(&self.acc) {
            Some(crate::Sensor::Acc)
        } else if none(&self.gyro) {
            Some(crate::Sensor::Gyro)
        } else {
            None
        }
    }

    /// For the analysers on a one-sensor topic: fills the absent sensor's NaN columns with
    /// `stand_in` and returns which sensor that is (`None`: both present, nothing changed).
    /// The stand-in only lets the six-axis machinery run (the record check reads zeros as
    /// a sensor that says nothing; the Allan step may mirror the present sensor); every
    /// output for the absent sensor is then omitted or marked absent by the caller.
    pub fn stand_in_absent(&mut self, stand_in: StandIn) -> Option<crate::Sensor> {
        let absent = self.absent_sensor()?;
        let (to, from) = match absent {
            crate::Sensor::Acc => (&mut self.acc, &self.gyro),
            crate::Sensor::Gyro => (&mut self.gyro, &self.acc),
        };
        for (t, f) in to.iter_mut().zip(from) {
            match stand_in {
                StandIn::Zeros => t.iter_mut().for_each(|v| *v = 0.0),
                StandIn::Mirror => t.clone_from(f),
            }
        }
        Some(absent)
    }

    /// Fails with [`Error::OneSensor`] when the topic lacks a sensor (for the analysers,
    /// which fit both).
    pub fn require_both_sensors(&self) -> Result<(), Error> {
        match self.absent_sensor() {
            Some(missing) => Err(Error::OneSensor {
                topic: self.topic.clone(),
                missing,
            }),
            None => Ok(()),
        }
    }

    /// A topic of integrated deltas whose rows do not tile the time is no sequence of
    /// samples: the [`crate::DeadTime`] error that says why (the rule:
    /// [`crate::check_integration`]). Every other topic passes.
    pub fn check_integration(&self) -> Result<(), Error> {
        Ok(crate::integrated::check(
            &self.topic,
            self.integration,
            &crate::timing::ns_of_times(&self.stamp),
        )?)
    }

    /// The chosen time column.
    pub fn time(&self, which: TimeColumn) -> &[RosTime] {
        match which {
            TimeColumn::Record => &self.record_time,
            TimeColumn::Header => &self.stamp,
        }
    }
}

/// The analysers' warning for a topic without `absent` (a one-sensor topic).
pub fn absent_warning(absent: crate::Sensor) -> crate::shared::note::Note {
    crate::shared::note::Note::warning(format!(
        "the topic carries no {} (a one-sensor topic): only the {} is analysed; the {} outputs are left out",
        absent.name(),
        absent.other().name(),
        absent.name()
    ))
}

/// What [`ImuSeries::stand_in_absent`] puts in an absent sensor's columns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StandIn {
    /// Zeros: a sensor that says nothing (the record check finds nothing on it).
    Zeros,
    /// The present sensor's columns (the computations run on real-looking data; their
    /// results for the absent sensor are discarded).
    Mirror,
}

/// Everything one pass over an input delivered.
#[derive(Debug, Clone)]
pub struct ImuRead {
    /// What the input is.
    pub kind: InputKind,
    /// One series per selected topic, in the order asked for (then the other Imu topics by
    /// name).
    pub series: Vec<ImuSeries>,
    /// Topics not read, with their type and promised count (skipped, not lost).
    pub skipped_topics: Vec<TopicSummary>,
    /// What the container found lost at the container level.
    pub losses: Vec<Loss>,
}

/// How a channel's payloads decode as Imu.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Codec {
    Ros1,
    Cdr,
    /// Rows a log reader decoded ([`crate::Row`]), whatever the topic's type.
    Row,
}

impl Codec {
    /// The smallest payload a message of this codec has.
    fn min_payload(self) -> u64 {
        match self {
            Codec::Ros1 | Codec::Cdr => MIN_IMU_PAYLOAD,
            Codec::Row => crate::rows::ROW_LEN as u64,
        }
    }
}

/// The Imu codec for a channel, or `None` when it does not carry `sensor_msgs/Imu`.
fn imu_codec(c: &Channel) -> Option<Codec> {
    if c.encoding == Encoding::Row {
        return Some(Codec::Row);
    }
    let imu_type = c.msg_type == imu_msg::TYPE || c.msg_type == crate::cdr::TYPE;
    match (&c.encoding, imu_type) {
        (Encoding::Ros1, true) => match &c.md5sum {
            Some(m) if m != imu_msg::MD5 && m != "*" => None,
            _ => Some(Codec::Ros1),
        },
        (Encoding::Cdr, true) => Some(Codec::Cdr),
        _ => None,
    }
}

/// True when the channel carries `sensor_msgs/Imu` in an encoding we decode.
pub(crate) fn is_imu(c: &Channel) -> bool {
    imu_codec(c).is_some()
}

fn decode(codec: Codec, data: &[u8]) -> Result<ImuSample, Error> {
    match codec {
        Codec::Ros1 => ImuSample::decode(data).map_err(Error::from),
        Codec::Cdr => crate::cdr::decode_sample(data),
        Codec::Row => crate::rows::Row::decode(data),
    }
}

/// Every topic of the source with its type and message count, sorted by topic. Counts the
/// container does not keep are counted by reading it.
pub(crate) fn topic_summaries(src: &dyn Source) -> Vec<TopicSummary> {
    let counts = channel_counts(src);
    let mut by: std::collections::BTreeMap<(String, String), u64> = Default::default();
    for c in src.channels() {
        *by.entry((c.topic.clone(), c.msg_type.clone())).or_default() +=
            counts.get(&c.id).copied().unwrap_or(0);
    }
    by.into_iter()
        .map(|((topic, msg_type), count)| TopicSummary {
            topic,
            msg_type,
            count,
        })
        .collect()
}

/// Messages per channel: the container's counts, or a counting pass when it has none.
pub(crate) fn channel_counts(src: &dyn Source) -> std::collections::BTreeMap<u32, u64> {
    if src.channels().iter().all(|c| c.count.is_some()) {
        return src
            .channels()
            .iter()
            .map(|c| (c.id, c.count.unwrap_or(0)))
            .collect();
    }
    let per_part: Vec<std::collections::BTreeMap<u32, u64>> = (0..src.parts().len())
        .into_par_iter()
        .map(|i| {
            let mut m = std::collections::BTreeMap::new();
            src.read_part(i, &|_| true, &mut |c, _, _| *m.entry(c).or_default() += 1);
            m
        })
        .collect();
    let mut total = std::collections::BTreeMap::new();
    for m in per_part {
        for (c, n) in m {
            *total.entry(c).or_default() += n;
        }
    }
    total
}

/// Parts decoded at once when the container does not say how many rows each holds: their
/// rows are buffered, then appended in order, so memory stays near the size of the result.
const WINDOW_PARTS_PER_THREAD: usize = 4;

/// Where one part's rows of one topic go: its planned slot, then (past the plan) a buffer.
#[derive(Default)]
struct Target<'a> {
    slot: RowsMut<'a>,
    filled: usize,
    overflow: Rows,
}

impl Target<'_> {
    fn put(&mut self, t: u64, s: &ImuSample) {
        if self.filled < self.slot.cap() {
            self.slot.set(self.filled, t, s);
            self.filled += 1;
        } else {
            self.overflow.push(t, s);
        }
    }

    /// [`Target::put`] for a decoded row (its seq stays 0: the column is left untouched).
    fn put_row(&mut self, t: u64, r: &crate::rows::Row) {
        if self.filled < self.slot.cap() {
            self.slot.set_row(self.filled, t, r);
            self.filled += 1;
        } else {
            self.overflow.push_row(t, r);
        }
    }

    fn rows(&self) -> usize {
        self.filled + self.overflow.len()
    }

    /// True when the part delivered exactly what its slot was sized for.
    fn exact(&self) -> bool {
        self.filled == self.slot.cap() && self.overflow.len() == 0
    }
}

/// What one part delivered, per selected topic (the rows themselves are in the targets).
struct PartOut {
    rows: Vec<u64>,
    bad: Vec<u64>,
    first_bad: Vec<Option<String>>,
    read: source::PartRead,
}

/// How part `i` routes a selected channel's messages: channel id → (topic, codec).
type Lookup = Vec<Option<(usize, Codec)>>;

/// Reads part `i` into `targets` (one per selected topic).
fn decode_part(
    src: &dyn Source,
    i: usize,
    lookup: &Lookup,
    targets: &mut [Target<'_>],
    pb: &indicatif::ProgressBar,
    per_part_unit: bool,
) -> PartOut {
    let n_sel = targets.len();
    let mut bad = vec![0u64; n_sel];
    let mut first_bad: Vec<Option<String>> = vec![None; n_sel];
    let want = |c: u32| lookup.get(c as usize).is_some_and(|x| x.is_some());
    // rows a log reader decoded go straight into the columns, without a payload
    let all_rows = lookup.iter().flatten().all(|(_, c)| *c == Codec::Row);
    let by_rows = if all_rows {
        src.read_part_rows(i, &want, &mut |c, t, row| {
            if let Some(Some((k, _))) = lookup.get(c as usize) {
                targets[*k].put_row(t, row);
            }
        })
    } else {
        None
    };
    let read = match by_rows {
        Some(read) => read,
        None => src.read_part(i, &want, &mut |c, t, data| {
            if let Some(Some((k, codec))) = lookup.get(c as usize) {
                match decode(*codec, data) {
                    Ok(s) => targets[*k].put(t, &s),
                    Err(e) => {
                        bad[*k] += 1;
                        first_bad[*k].get_or_insert_with(|| e.to_string());
                    }
                }
            }
        }),
    };
    pb.inc(if per_part_unit { 1 } else { read.delivered });
    PartOut {
        rows: targets.iter().map(|t| t.rows() as u64).collect(),
        bad,
        first_bad,
        read,
    }
}

/// Decodes every part into one [`Rows`] per selected topic, in storage order.
///
/// When every part says how many messages of each topic it holds, the columns are allocated
/// once and each part is decoded in parallel straight into its own rows (no copy). A part
/// that holds more or fewer than it said is still read whole (its extra rows are buffered)
/// and the columns are then rebuilt in order. Without counts, parts are decoded a window at
/// a time and appended, so memory stays near the size of the result. Slots are sized by the
/// counts bounded by what the part's bytes can hold ([`MIN_IMU_PAYLOAD`]).
fn decode_all(
    src: &dyn Source,
    lookup: &Lookup,
    selected: &[Selected],
    pb: &indicatif::ProgressBar,
    per_part_unit: bool,
) -> (Vec<Rows>, Vec<PartOut>) {
    let parts = src.parts();
    let n_sel = selected.len();
    match part_plan(parts, lookup, selected) {
        Some(plan) => decode_planned(src, lookup, &plan, n_sel, pb, per_part_unit),
        None => decode_windowed(src, lookup, n_sel, pb, per_part_unit),
    }
}

/// The rows of each selected topic each part holds (`plan[i][k]`: topic `k` in part `i`),
/// when every part counts its messages; bounded by what the part's bytes can hold.
fn part_plan(
    parts: &[source::Part],
    lookup: &Lookup,
    selected: &[Selected],
) -> Option<Vec<Vec<usize>>> {
    parts
        .iter()
        .map(|p| {
            let counts = p.counts.as_ref()?;
            let min_payload = selected
                .iter()
                .flat_map(|s| s.channels.iter().map(|(_, k)| k.min_payload()))
                .min()
                .unwrap_or(MIN_IMU_PAYLOAD);
            let bound = p.bytes / min_payload;
            Some(
                selected
                    .iter()
                    .map(|s| {
                        // channels the parts deliver (not those taken whole)
                        let n: u64 = counts
                            .iter()
                            .filter(|(c, _)| lookup.get(*c as usize).is_some_and(|x| x.is_some()))
                            .filter(|(c, _)| s.channels.iter().any(|(id, _)| id == c))
                            .map(|(_, n)| *n)
                            .fold(0u64, |a, b| a.saturating_add(b));
                        n.min(bound) as usize
                    })
                    .collect(),
            )
        })
        .collect()
}

/// The parts decoded in parallel straight into their slots of columns sized by `plan`;
/// when a part disagrees with its count, the columns are rebuilt in order.
fn decode_planned(
    src: &dyn Source,
    lookup: &Lookup,
    plan: &[Vec<usize>],
    n_sel: usize,
    pb: &indicatif::ProgressBar,
    per_part_unit: bool,
) -> (Vec<Rows>, Vec<PartOut>) {
    let parts = src.parts();
    let mut columns: Vec<Rows> = (0..n_sel)
        .map(|k| Rows::zeroed(plan.iter().map(|p| p[k]).sum()))
        .collect();
    let outs: Vec<PartOut>;
    {
        // slots[k][i]: topic k's rows of part i.
        let mut slots: Vec<std::vec::IntoIter<RowsMut>> = columns
            .iter_mut()
            .enumerate()
            .map(|(k, c)| {
                let sizes: Vec<usize> = plan.iter().map(|p| p[k]).collect();
                c.split(&sizes).into_iter()
            })
            .collect();
        let mut per_part: Vec<Vec<Target>> = (0..parts.len())
            .map(|_| {
                slots
                    .iter_mut()
                    .map(|it| Target {
                        slot: it.next().unwrap_or_default(),
                        ..Target::default()
                    })
                    .collect()
            })
            .collect();
        outs = per_part
            .par_iter_mut()
            .enumerate()
            .map(|(i, targets)| decode_part(src, i, lookup, targets, pb, per_part_unit))
            .collect();
        if per_part.iter().flatten().any(|t| !t.exact()) {
            // Some part disagreed with its count: gather the rows in order.
            let mut r: Vec<Rows> = (0..n_sel).map(|_| Rows::default()).collect();
            for targets in &per_part {
                for (k, t) in targets.iter().enumerate() {
                    r[k].extend_from(&t.slot, t.filled);
                    r[k].append(&t.overflow);
                }
            }
            return (r, outs);
        }
    }
    (columns, outs)
}

/// The parts decoded a window at a time and appended (no counts to size the columns):
/// memory stays near the size of the result.
fn decode_windowed(
    src: &dyn Source,
    lookup: &Lookup,
    n_sel: usize,
    pb: &indicatif::ProgressBar,
    per_part_unit: bool,
) -> (Vec<Rows>, Vec<PartOut>) {
    let parts = src.parts();
    let mut columns: Vec<Rows> = (0..n_sel).map(|_| Rows::default()).collect();
    let mut outs = Vec::with_capacity(parts.len());
    let window = (rayon::current_num_threads() * WINDOW_PARTS_PER_THREAD).max(1);
    let mut start = 0;
    while start < parts.len() {
        let end = (start + window).min(parts.len());
        let done: Vec<(Vec<Target>, PartOut)> = (start..end)
            .into_par_iter()
            .map(|i| {
                let mut targets: Vec<Target> = (0..n_sel).map(|_| Target::default()).collect();
                let o = decode_part(src, i, lookup, &mut targets, pb, per_part_unit);
                (targets, o)
            })
            .collect();
        for (targets, o) in done {
            for (k, t) in targets.iter().enumerate() {
                columns[k].append(&t.overflow);
            }
            outs.push(o);
        }
        start = end;
    }
    (columns, outs)
}

/// [`crate::read_imu_topics`] on an open source.
pub fn read_from(
    src: &dyn Source,
    sel: &TopicSelector,
    opts: &ReadOptions,
) -> Result<ImuRead, Error> {
    read_source(src, sel, opts, false)
}

/// [`read_from`] on a source read once and dropped: a topic its reader decoded whole on
/// opening moves into the series ([`Source::take_rows`]) instead of being copied.
pub(crate) fn read_owned(
    src: Box<dyn Source>,
    sel: &TopicSelector,
    opts: &ReadOptions,
) -> Result<ImuRead, Error> {
    read_source(src.as_ref(), sel, opts, true)
}

fn read_source(
    src: &dyn Source,
    sel: &TopicSelector,
    opts: &ReadOptions,
    take: bool,
) -> Result<ImuRead, Error> {
    let selected = select(src, sel)?;
    let mut lookup = channel_lookup(src, &selected);
    let promised: Vec<Option<u64>> = selected
        .iter()
        .map(|s| promised_of(src, &s.channels))
        .collect();
    let (columns, outs) = read_columns(src, &selected, &mut lookup, &promised, opts, take);
    let after = src.losses_after_read();
    // each topic in record-time order, the topics in parallel (a pass over every row each)
    let columns: Vec<(Rows, Option<Vec<u32>>)> = columns
        .into_par_iter()
        .map(|mut rows| {
            let order = rows.sort_by_record_time();
            (rows, order)
        })
        .collect();

    let n_sel = selected.len();
    let mut series = Vec::with_capacity(n_sel);
    let mut dropped: Vec<Note> = Vec::new();
    for ((k, s), rows) in selected.into_iter().enumerate().zip(columns) {
        let out = topic_series(src, &s, k, rows, promised[k], &outs, &after);
        if out.is_empty() {
            // Nothing to convert is an error for a topic the user named; an Imu topic that
            // --all-imu-topics found empty is left out, and said so.
            if s.named || series.is_empty() && k + 1 == n_sel && dropped.len() + 1 == n_sel {
                return Err(Error::NothingRead {
                    topic: s.topic.clone(),
                    why: out.notes.iter().map(|n| n.text.clone()).collect(),
                });
            }
            dropped.push(Note::warning(format!(
                "Imu topic '{}' holds no readable message and was left out",
                s.topic
            )));
            continue;
        }
        series.push(out);
    }
    for s in series.iter_mut() {
        s.notes.extend(dropped.iter().cloned());
    }
    Ok(ImuRead {
        kind: src.kind(),
        series,
        skipped_topics: skipped_topics(src, &lookup),
        losses: src.losses().iter().chain(after.iter()).cloned().collect(),
    })
}

/// Channel id → (selected topic, codec); a dense table for the usual small ids.
fn channel_lookup(src: &dyn Source, selected: &[Selected]) -> Lookup {
    let max_id = src.channels().iter().map(|c| c.id).max().unwrap_or(0) as usize;
    let mut lookup: Lookup = vec![None; max_id + 1];
    for (k, s) in selected.iter().enumerate() {
        for &(id, codec) in &s.channels {
            lookup[id as usize] = Some((k, codec));
        }
    }
    lookup
}

/// The messages the container promises on these channels, if it counts them all.
fn promised_of(src: &dyn Source, ids: &[(u32, Codec)]) -> Option<u64> {
    ids.iter()
        .map(|(id, _)| src.channels().iter().find(|c| c.id == *id)?.count)
        .sum()
}

/// Reads the parts once, with a progress bar: the selected topics' rows and what each part
/// delivered. A topic of one channel of rows its reader decoded whole is taken as it is
/// (`take`); the parts then deliver only the other topics (its channels leave `lookup`).
fn read_columns(
    src: &dyn Source,
    selected: &[Selected],
    lookup: &mut Lookup,
    promised: &[Option<u64>],
    opts: &ReadOptions,
    take: bool,
) -> (Vec<Rows>, Vec<PartOut>) {
    let parts = src.parts();
    let (bar_len, per_part_unit) = match promised.iter().copied().sum::<Option<u64>>() {
        Some(n) => (n, false),
        None => (parts.len() as u64, true),
    };
    let pb = crate::shared::progress::bar(
        bar_len.max(1),
        opts.quiet,
        if per_part_unit { "parts" } else { "msgs" },
    );
    pb.set_message("reading");
    let taken: Vec<Option<Rows>> = selected
        .iter()
        .map(|s| match s.channels[..] {
            [(id, Codec::Row)] if take => src.take_rows(id),
            _ => None,
        })
        .collect();
    for (s, t) in selected.iter().zip(&taken) {
        if t.is_some() {
            s.channels
                .iter()
                .for_each(|(id, _)| lookup[*id as usize] = None);
            pb.inc(t.as_ref().map_or(0, |r| r.len() as u64));
        }
    }
    let (mut columns, mut outs) = decode_all(src, lookup, selected, &pb, per_part_unit);
    for (k, (s, t)) in selected.iter().zip(taken).enumerate() {
        let Some(rows) = t else { continue };
        // what each part holds of the topic, as if its parts had delivered them
        for (o, p) in outs.iter_mut().zip(parts) {
            let n: u64 = p
                .counts
                .iter()
                .flatten()
                .filter(|(c, _)| s.channels.iter().any(|(id, _)| id == c))
                .map(|(_, n)| *n)
                .sum();
            o.rows[k] = n;
            o.read.delivered += n;
        }
        columns[k] = rows;
    }
    pb.finish_and_clear();
    (columns, outs)
}

/// Topic `k`'s series from its rows in record-time order (and where each was stored, when
/// sorting moved them): its report (promised, delivered, undecodable, the losses of its
/// parts and of the container) and its notes.
fn topic_series(
    src: &dyn Source,
    s: &Selected,
    k: usize,
    (rows, storage_order): (Rows, Option<Vec<u32>>),
    promised: Option<u64>,
    outs: &[PartOut],
    after: &[Loss],
) -> ImuSeries {
    let sorted = storage_order.is_some();
    let Rows {
        record_time,
        stamp,
        seq,
        acc,
        gyro,
    } = rows;
    let integration = match s.channels[..] {
        [(id, _)] => src
            .contents()
            .integration
            .iter()
            .find(|(c, _)| *c == id)
            .map(|(_, i)| *i),
        _ => None,
    };
    let mut out = ImuSeries {
        topic: s.topic.clone(),
        msg_type: s.msg_type.clone(),
        record_time,
        stamp,
        seq,
        acc,
        gyro,
        storage_order,
        integration,
        ..ImuSeries::default()
    };
    let r = &mut out.report;
    r.promised = promised;
    r.delivered = out.record_time.len() as u64;
    for o in outs {
        r.undecodable += o.bad[k];
        if r.first_error.is_none() {
            r.first_error = o.first_bad[k].clone();
        }
    }
    let mine_ch = |c: &u32| s.channels.iter().any(|(id, _)| id == c);
    let mut tally = LossTally {
        only_topic: src.channels().iter().all(|c| mine_ch(&c.id)),
        ..LossTally::default()
    };
    part_losses(src.parts(), outs, k, s, r, &mut tally);
    let container: Vec<&Loss> = src
        .losses()
        .iter()
        .chain(after.iter())
        .filter(|l| l.channel.is_none_or(|c| mine_ch(&c)))
        .collect();
    for l in &container {
        tally.count(l, l.channel.is_some());
    }
    let mut notes: Vec<Note> = src.notes().to_vec();
    for o in outs {
        notes.extend(o.read.notes.iter().cloned());
    }
    // the container's losses, but another topic's own (a loss that names its channel)
    notes.extend(container.iter().map(|l| Note::warning(l.to_string())));
    notes.extend(s.note.iter().cloned().map(Note::warning));
    notes.extend(r.losses.iter().map(|l| Note::warning(l.to_string())));
    loss_notes(&mut notes, r, &s.topic, &tally, container.is_empty());
    if sorted {
        notes.push(Note::warning(SORTED_NOTE));
    }
    out.notes = notes;
    out
}

const SORTED_NOTE: &str =
    "messages were not stored in record-time order; sorted as rosbag::View does";

/// A folder name for each topic, for tools that write one output folder per topic: the
/// topic without its leading slash, other slashes as `_` (`/cam0/imu` → `cam0_imu`), and a
/// numeric suffix where two topics would otherwise share a folder (`imu` and `/imu`).
pub fn topic_folder_names(topics: &[&str]) -> Vec<String> {
    let mut out: Vec<String> = Vec::with_capacity(topics.len());
    for t in topics {
        let base: String = t
            .trim_start_matches('/')
            .chars()
            .map(|c| {
                if c == '/' || c == '\\' || c.is_control() {
                    '_'
                } else {
                    c
                }
            })
            .collect();
        let base = if base.is_empty() || base == "." || base == ".." {
            "topic".to_string()
        } else {
            base
        };
        let mut name = base.clone();
        let mut k = 2;
        while out.contains(&name) {
            name = format!("{base}_{k}");
            k += 1;
        }
        out.push(name);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folder_names_are_unique_and_flat() {
        assert_eq!(
            topic_folder_names(&["/imu0", "/cam0/imu", "imu", "/imu", "/", ".."]),
            vec!["imu0", "cam0_imu", "imu", "imu_2", "topic", "topic_2"]
        );
    }
}
