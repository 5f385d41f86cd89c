//! The one read path: Imu topics of any input as columns, in record-time order — what
//! `bag2mat` converts and both analysers consume.
//!
//! On top of a [`Source`] (any container), written once for every format: the topic rules
//! (exact name, else the other slash form with a note; `--all-imu-topics`), the missing-topic
//! error that lists every topic with type and count, the type check, the progress bar, the
//! parallel decode of the parts (ROS 1 or CDR codec, straight into the columns), the stable
//! sort by record time (as `rosbag::View` and rosbag2's reader deliver messages), and the
//! accounting of what the container promised against what was delivered ([`TopicReport`]).

use std::path::Path;

use rayon::prelude::*;

use crate::bag::RosTime;
use crate::error::{Error, TopicSummary};
use crate::imu_msg::{self, ImuSample};
use crate::source::{self, Channel, Encoding, InputKind, Loss, Source};

/// How to read.
#[derive(Debug, Clone, Copy, Default)]
pub struct ReadOptions {
    /// No progress bar.
    pub quiet: bool,
}

/// Which topics to read.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct TopicSelector {
    /// Topics by name (each tried in the other slash form when missing).
    pub topics: Vec<String>,
    /// Every topic that carries `sensor_msgs/Imu`, besides the named ones.
    pub all_imu: bool,
}

impl TopicSelector {
    /// One named topic.
    pub fn one(topic: &str) -> TopicSelector {
        TopicSelector {
            topics: vec![topic.to_string()],
            all_imu: false,
        }
    }
}

/// Which time goes into the time column.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
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
    /// Linear acceleration `[x, y, z]`, m/s².
    pub acc: Vec<[f64; 3]>,
    /// Angular velocity `[x, y, z]`, rad/s.
    pub gyro: Vec<[f64; 3]>,
    /// Things the binary should tell the user on stderr (topic fallback, lost chunks, …).
    pub notes: Vec<String>,
    /// Promised against delivered.
    pub report: TopicReport,
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

    /// The chosen time column.
    pub fn time(&self, which: TimeColumn) -> &[RosTime] {
        match which {
            TimeColumn::Record => &self.record_time,
            TimeColumn::Header => &self.stamp,
        }
    }
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
}

/// The Imu codec for a channel, or `None` when it does not carry `sensor_msgs/Imu`.
fn imu_codec(c: &Channel) -> Option<Codec> {
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
pub fn is_imu(c: &Channel) -> bool {
    imu_codec(c).is_some()
}

fn decode(codec: Codec, data: &[u8]) -> Result<ImuSample, Error> {
    match codec {
        Codec::Ros1 => ImuSample::decode(data),
        Codec::Cdr => crate::cdr::decode_sample(data),
    }
}

/// Every topic of the source with its type and message count, sorted by topic. Counts the
/// container does not keep are counted by reading it.
pub fn topic_summaries(src: &dyn Source) -> Vec<TopicSummary> {
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
pub fn channel_counts(src: &dyn Source) -> std::collections::BTreeMap<u32, u64> {
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

/// A selected topic: its name in the bag, its channels and how they decode.
struct Selected {
    topic: String,
    msg_type: String,
    channels: Vec<(u32, Codec)>,
    note: Option<String>,
}

fn other_slash_form(topic: &str) -> String {
    match topic.strip_prefix('/') {
        Some(rest) => rest.to_string(),
        None => format!("/{topic}"),
    }
}

fn select(src: &dyn Source, sel: &TopicSelector) -> Result<Vec<Selected>, Error> {
    let chans = src.channels();
    let on = |t: &str| chans.iter().filter(|c| c.topic == t).collect::<Vec<_>>();
    let mut out: Vec<Selected> = Vec::new();
    let push = |out: &mut Vec<Selected>, topic: String, cs: Vec<&Channel>, note| {
        if out.iter().any(|s| s.topic == topic) {
            return Ok(());
        }
        let mut channels = Vec::new();
        for c in &cs {
            match imu_codec(c) {
                Some(k) => channels.push((c.id, k)),
                None => {
                    return Err(Error::WrongType {
                        topic: topic.clone(),
                        msg_type: c.msg_type.clone(),
                        md5sum: c
                            .md5sum
                            .clone()
                            .unwrap_or_else(|| format!("encoding {}", c.encoding.name())),
                    });
                }
            }
        }
        out.push(Selected {
            topic,
            msg_type: cs[0].msg_type.clone(),
            channels,
            note,
        });
        Ok(())
    };
    for t in &sel.topics {
        let cs = on(t);
        if !cs.is_empty() {
            push(&mut out, t.clone(), cs, None)?;
            continue;
        }
        let other = other_slash_form(t);
        let cs = on(&other);
        if cs.is_empty() {
            return Err(Error::TopicNotFound {
                topic: t.clone(),
                available: topic_summaries(src),
            });
        }
        let note = format!("topic '{t}' is not in the bag; using '{other}'");
        push(&mut out, other, cs, Some(note))?;
    }
    if sel.all_imu {
        let mut topics: Vec<&str> = chans
            .iter()
            .filter(|c| is_imu(c))
            .map(|c| c.topic.as_str())
            .collect();
        topics.sort();
        topics.dedup();
        let before = out.len();
        for t in topics {
            // A topic that mixes Imu with another type is not "an Imu topic".
            let cs = on(t);
            if cs.iter().all(|c| is_imu(c)) {
                push(&mut out, t.to_string(), cs, None)?;
            }
        }
        if out.is_empty() && before == 0 {
            return Err(Error::NoImuTopic {
                available: topic_summaries(src),
            });
        }
    }
    Ok(out)
}

/// One decoded message.
#[derive(Clone, Copy)]
struct Row {
    t: u64,
    s: ImuSample,
}

/// What one part delivered, per selected topic: the messages written straight into its
/// slice of the columns, and those beyond it (or all, without a promised count) as rows.
struct PartOut {
    written: Vec<usize>,
    rows: Vec<Vec<Row>>,
    bad: Vec<u64>,
    first_bad: Vec<Option<String>>,
    read: source::PartRead,
}

/// One part's slice of one topic's columns.
struct Slices<'a> {
    record_time: &'a mut [RosTime],
    stamp: &'a mut [RosTime],
    seq: &'a mut [u32],
    acc: &'a mut [[f64; 3]],
    gyro: &'a mut [[f64; 3]],
}

impl Slices<'_> {
    fn len(&self) -> usize {
        self.record_time.len()
    }

    fn set(&mut self, i: usize, t: u64, s: &ImuSample) {
        self.record_time[i] = RosTime::from_nanos(t);
        self.stamp[i] = s.stamp;
        self.seq[i] = s.seq;
        self.acc[i] = s.acc;
        self.gyro[i] = s.gyro;
    }
}

/// Splits a column into one slice per part, of the given lengths.
fn split_rows<'a, T>(column: &'a mut [T], sizes: &[usize]) -> Vec<&'a mut [T]> {
    let mut rest = column;
    sizes
        .iter()
        .map(|&k| {
            let (head, tail) = std::mem::take(&mut rest).split_at_mut(k);
            rest = tail;
            head
        })
        .collect()
}

/// Reads the selected Imu topics of `path` (any accepted input) in one pass.
pub fn read_imu_topics(
    path: &Path,
    sel: &TopicSelector,
    opts: &ReadOptions,
) -> Result<ImuRead, Error> {
    let src = source::open(path)?;
    read_from(src.as_ref(), sel, opts)
}

/// [`read_imu_topics`] on an open source.
pub fn read_from(
    src: &dyn Source,
    sel: &TopicSelector,
    opts: &ReadOptions,
) -> Result<ImuRead, Error> {
    let selected = select(src, sel)?;
    let n_sel = selected.len();
    // Channel id → (selected topic, codec); a dense table for the usual small ids.
    let max_id = src.channels().iter().map(|c| c.id).max().unwrap_or(0) as usize;
    let mut lookup: Vec<Option<(usize, Codec)>> = vec![None; max_id + 1];
    for (k, s) in selected.iter().enumerate() {
        for &(id, codec) in &s.channels {
            lookup[id as usize] = Some((k, codec));
        }
    }
    let want = |c: u32| lookup.get(c as usize).is_some_and(|x| x.is_some());
    let promised_of = |ids: &[(u32, Codec)]| -> Option<u64> {
        ids.iter()
            .map(|(id, _)| src.channels().iter().find(|c| c.id == *id)?.count)
            .sum()
    };
    let promised: Vec<Option<u64>> = selected.iter().map(|s| promised_of(&s.channels)).collect();
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
    // Each part's promised count of each topic. Where every part states one, the topic's
    // columns are allocated once at their final size and each part decodes straight into
    // its own slice of them: the read holds one copy of the data, not rows and columns.
    let expect: Vec<Vec<Option<usize>>> = parts
        .iter()
        .map(|p| {
            (0..n_sel)
                .map(|k| {
                    p.counts.as_ref().map(|v| {
                        v.iter()
                            .filter(|(c, _)| selected[k].channels.iter().any(|(id, _)| id == c))
                            .map(|(_, n)| *n as usize)
                            .sum()
                    })
                })
                .collect()
        })
        .collect();
    let direct: Vec<bool> = (0..n_sel)
        .map(|k| expect.iter().all(|e| e[k].is_some()))
        .collect();
    let mut cols: Vec<ImuSeries> = (0..n_sel)
        .map(|k| {
            let n = if direct[k] {
                expect.iter().map(|e| e[k].unwrap_or(0)).sum()
            } else {
                0
            };
            ImuSeries {
                record_time: vec![RosTime::default(); n],
                stamp: vec![RosTime::default(); n],
                seq: vec![0; n],
                acc: vec![[0.0; 3]; n],
                gyro: vec![[0.0; 3]; n],
                ..ImuSeries::default()
            }
        })
        .collect();
    let sizes: Vec<Vec<usize>> = (0..n_sel)
        .map(|k| {
            expect
                .iter()
                .map(|e| if direct[k] { e[k].unwrap_or(0) } else { 0 })
                .collect()
        })
        .collect();
    let mut dests: Vec<Vec<Slices>> = (0..parts.len())
        .map(|_| Vec::with_capacity(n_sel))
        .collect();
    for (c, sz) in cols.iter_mut().zip(&sizes) {
        let sl = split_rows(&mut c.record_time, sz)
            .into_iter()
            .zip(split_rows(&mut c.stamp, sz))
            .zip(split_rows(&mut c.seq, sz))
            .zip(split_rows(&mut c.acc, sz))
            .zip(split_rows(&mut c.gyro, sz));
        for (d, ((((record_time, stamp), seq), acc), gyro)) in dests.iter_mut().zip(sl) {
            d.push(Slices {
                record_time,
                stamp,
                seq,
                acc,
                gyro,
            });
        }
    }
    let outs: Vec<PartOut> = dests
        .into_par_iter()
        .enumerate()
        .map(|(i, mut dst)| {
            let mut written = vec![0usize; n_sel];
            let mut rows: Vec<Vec<Row>> = vec![Vec::new(); n_sel];
            let mut bad = vec![0u64; n_sel];
            let mut first_bad: Vec<Option<String>> = vec![None; n_sel];
            let read = src.read_part(i, &want, &mut |c, t, data| {
                if let Some(Some((k, codec))) = lookup.get(c as usize) {
                    match decode(*codec, data) {
                        Ok(s) if written[*k] < dst[*k].len() => {
                            dst[*k].set(written[*k], t, &s);
                            written[*k] += 1;
                        }
                        Ok(s) => rows[*k].push(Row { t, s }),
                        Err(e) => {
                            bad[*k] += 1;
                            first_bad[*k].get_or_insert_with(|| e.to_string());
                        }
                    }
                }
            });
            pb.inc(if per_part_unit { 1 } else { read.delivered });
            PartOut {
                written,
                rows,
                bad,
                first_bad,
                read,
            }
        })
        .collect();
    pb.finish_and_clear();

    let mut series = Vec::with_capacity(n_sel);
    for ((k, s), cols_k) in selected.into_iter().enumerate().zip(cols) {
        let got_of: Vec<u64> = outs
            .iter()
            .map(|o| (o.written[k] + o.rows[k].len()) as u64)
            .collect();
        let mut out = assemble(cols_k, &sizes[k], &outs, k);
        out.topic = s.topic.clone();
        out.msg_type = s.msg_type.clone();
        let r = &mut out.report;
        r.promised = promised[k];
        r.delivered = out.record_time.len() as u64;
        for o in &outs {
            r.undecodable += o.bad[k];
            if r.first_error.is_none() {
                r.first_error = o.first_bad[k].clone();
            }
        }
        for (i, o) in outs.iter().enumerate() {
            let p = &parts[i];
            let mine: Option<u64> = p.counts.as_ref().map(|v| {
                v.iter()
                    .filter(|(c, _)| s.channels.iter().any(|(id, _)| id == c))
                    .map(|(_, n)| *n)
                    .sum()
            });
            let got = got_of[i] + o.bad[k];
            let reason = match (&o.read.error, o.read.skipped) {
                (Some(e), _) => Some(e.clone()),
                (None, n) if n > 0 => o.read.skip_reason.clone(),
                _ => None,
            };
            let short = mine.is_some_and(|m| got < m);
            if let Some(reason) = reason {
                if mine == Some(0) {
                    continue;
                }
                r.losses.push(Loss {
                    what: format!("{}: {reason}", p.label),
                    messages: mine.map(|m| m.saturating_sub(got)),
                    span: p.span,
                });
            } else if short {
                r.losses.push(Loss {
                    what: format!(
                        "{} holds {got} messages of '{}', its index says {}",
                        p.label,
                        s.topic,
                        mine.unwrap_or(0)
                    ),
                    messages: mine.map(|m| m - got),
                    span: p.span,
                });
            }
        }
        let mut notes: Vec<String> = src.notes().to_vec();
        notes.extend(src.losses().iter().map(|l| l.to_string()));
        notes.extend(s.note.iter().cloned());
        notes.extend(r.losses.iter().map(|l| l.to_string()));
        let lost: u64 = r.losses.iter().filter_map(|l| l.messages).sum();
        if lost > 0 {
            notes.push(format!(
                "{lost} of {} messages were lost to unreadable chunks",
                r.promised.unwrap_or(r.delivered + lost)
            ));
        }
        if r.undecodable > 0 {
            notes.push(format!(
                "{} messages on '{}' do not decode as sensor_msgs/Imu and were skipped (first: {})",
                r.undecodable,
                s.topic,
                r.first_error.as_deref().unwrap_or("?")
            ));
        }
        if out.notes.iter().any(|n| n == SORTED_NOTE) {
            notes.push(SORTED_NOTE.to_string());
        }
        out.notes = notes;
        series.push(out);
    }
    let read_ids: std::collections::BTreeSet<u32> = lookup
        .iter()
        .enumerate()
        .filter(|(_, x)| x.is_some())
        .map(|(i, _)| i as u32)
        .collect();
    let mut skipped: std::collections::BTreeMap<(String, String), u64> = Default::default();
    for c in src.channels().iter().filter(|c| !read_ids.contains(&c.id)) {
        *skipped
            .entry((c.topic.clone(), c.msg_type.clone()))
            .or_default() += c.count.unwrap_or(0);
    }
    Ok(ImuRead {
        kind: src.kind(),
        series,
        skipped_topics: skipped
            .into_iter()
            .map(|((topic, msg_type), count)| TopicSummary {
                topic,
                msg_type,
                count,
            })
            .collect(),
        losses: src.losses().to_vec(),
    })
}

const SORTED_NOTE: &str =
    "messages were not stored in record-time order; sorted as rosbag::View does";

/// Topic `k`'s columns: `cols` as the parts filled their slices (of `sizes`), when each
/// delivered exactly what it promised; otherwise (no promise, fewer or more messages) the
/// parts' slices and rows gathered in part order. Then sorted by record time when the
/// storage order differs from it.
fn assemble(cols: ImuSeries, sizes: &[usize], outs: &[PartOut], k: usize) -> ImuSeries {
    let exact = outs
        .iter()
        .zip(sizes)
        .all(|(o, &n)| o.written[k] == n && o.rows[k].is_empty());
    let mut s = if exact {
        cols
    } else {
        let n: usize = outs.iter().map(|o| o.written[k] + o.rows[k].len()).sum();
        let mut s = ImuSeries {
            record_time: Vec::with_capacity(n),
            stamp: Vec::with_capacity(n),
            seq: Vec::with_capacity(n),
            acc: Vec::with_capacity(n),
            gyro: Vec::with_capacity(n),
            ..ImuSeries::default()
        };
        let mut off = 0;
        for (o, &size) in outs.iter().zip(sizes) {
            let r = off..off + o.written[k];
            s.record_time
                .extend_from_slice(&cols.record_time[r.clone()]);
            s.stamp.extend_from_slice(&cols.stamp[r.clone()]);
            s.seq.extend_from_slice(&cols.seq[r.clone()]);
            s.acc.extend_from_slice(&cols.acc[r.clone()]);
            s.gyro.extend_from_slice(&cols.gyro[r]);
            let rows = &o.rows[k];
            s.record_time
                .extend(rows.iter().map(|r| RosTime::from_nanos(r.t)));
            s.stamp.extend(rows.iter().map(|r| r.s.stamp));
            s.seq.extend(rows.iter().map(|r| r.s.seq));
            s.acc.extend(rows.iter().map(|r| r.s.acc));
            s.gyro.extend(rows.iter().map(|r| r.s.gyro));
            off += size;
        }
        s
    };
    if s.record_time.windows(2).any(|w| w[1] < w[0]) {
        let n = s.record_time.len();
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by_key(|&i| s.record_time[i]);
        s.record_time = permute(&s.record_time, &order);
        s.stamp = permute(&s.stamp, &order);
        s.seq = permute(&s.seq, &order);
        s.acc = permute(&s.acc, &order);
        s.gyro = permute(&s.gyro, &order);
        s.notes.push(SORTED_NOTE.to_string());
    }
    s
}

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

/// Reads one Imu topic (see [`read_imu_topics`] for the rules and errors).
pub fn read_imu_series(path: &Path, topic: &str, opts: &ReadOptions) -> Result<ImuSeries, Error> {
    let mut r = read_imu_topics(path, &TopicSelector::one(topic), opts)?;
    Ok(r.series.remove(0))
}

/// `v` reordered so that element `i` is `v[order[i]]`.
pub fn permute<T: Copy>(v: &[T], order: &[usize]) -> Vec<T> {
    order.iter().map(|&i| v[i]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(i: u32) -> ImuSample {
        ImuSample {
            seq: i,
            stamp: RosTime::from_nanos(1000 * i as u64),
            gyro: [i as f64; 3],
            acc: [-(i as f64); 3],
        }
    }

    fn part(written: usize, rows: Vec<Row>) -> PartOut {
        PartOut {
            written: vec![written],
            rows: vec![rows],
            bad: vec![0],
            first_bad: vec![None],
            read: source::PartRead::default(),
        }
    }

    /// Columns as the parts filled them: three parts promised 2 + 2 + 2 messages; the first
    /// delivered them, the second one short, the third one more (a row).
    fn filled() -> (ImuSeries, Vec<usize>) {
        let mut s = ImuSeries {
            record_time: vec![RosTime::default(); 6],
            stamp: vec![RosTime::default(); 6],
            seq: vec![0; 6],
            acc: vec![[0.0; 3]; 6],
            gyro: vec![[0.0; 3]; 6],
            ..ImuSeries::default()
        };
        for (slot, i) in [(0usize, 0u32), (1, 1), (2, 2), (4, 3), (5, 4)] {
            s.record_time[slot] = RosTime::from_nanos(10 * i as u64);
            s.stamp[slot] = sample(i).stamp;
            s.seq[slot] = i;
            s.acc[slot] = sample(i).acc;
            s.gyro[slot] = sample(i).gyro;
        }
        (s, vec![2, 2, 2])
    }

    #[test]
    fn assemble_keeps_exact_parts_and_gathers_the_rest_in_part_order() {
        // every part as promised: the columns as they are (the same buffers)
        let (mut cols, sizes) = filled();
        cols.record_time[3] = RosTime::from_nanos(25);
        cols.seq[3] = 9;
        let before = cols.seq.as_ptr();
        let exact = [part(2, vec![]), part(2, vec![]), part(2, vec![])];
        let got = assemble(cols, &sizes, &exact, 0);
        assert_eq!(got.seq, vec![0, 1, 2, 9, 3, 4]);
        assert_eq!(got.seq.as_ptr(), before, "no copy");
        let (cols, sizes) = filled();
        // a short part and a part with one more: its slice, then its row, in part order
        let uneven = [
            part(2, vec![]),
            part(1, vec![]),
            part(
                2,
                vec![Row {
                    t: 50,
                    s: sample(5),
                }],
            ),
        ];
        let got = assemble(cols, &sizes, &uneven, 0);
        assert_eq!(got.seq, vec![0, 1, 2, 3, 4, 5]);
        assert_eq!(
            got.record_time,
            (0..6)
                .map(|i| RosTime::from_nanos(10 * i))
                .collect::<Vec<_>>()
        );
        assert_eq!(got.acc[5], [-5.0; 3]);
        assert!(got.notes.is_empty(), "already in record-time order");
    }

    #[test]
    fn folder_names_are_unique_and_flat() {
        assert_eq!(
            topic_folder_names(&["/imu0", "/cam0/imu", "imu", "/imu", "/", ".."]),
            vec!["imu0", "cam0_imu", "imu", "imu_2", "topic", "topic_2"]
        );
    }
}
