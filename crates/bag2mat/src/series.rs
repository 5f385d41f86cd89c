//! One Imu topic of a bag as columns, in record-time order: what both analysers consume.

use std::path::Path;

use crate::bag::RosTime;
use crate::bag::read::{BagReader, StreamReport};
use crate::error::Error;

/// How to read.
#[derive(Debug, Clone, Copy, Default)]
pub struct ReadOptions {
    /// No progress bar.
    pub quiet: bool,
}

/// The Imu samples of one topic, in record-time order (as `rosbag::View` and `rosbag play`
/// deliver them).
#[derive(Debug, Clone, Default)]
pub struct ImuSeries {
    /// The topic as it is named in the bag.
    pub topic: String,
    /// Bag record (receive) time of each message.
    pub record_time: Vec<RosTime>,
    /// `header.stamp` of each message.
    pub stamp: Vec<RosTime>,
    /// `header.seq` of each message.
    pub seq: Vec<u32>,
    /// Linear acceleration `[x, y, z]`, m/s².
    pub acc: Vec<[f64; 3]>,
    /// Angular velocity `[x, y, z]`, rad/s.
    pub gyro: Vec<[f64; 3]>,
    /// Things the binary should tell the user on stderr (topic fallback, lost chunks).
    pub notes: Vec<String>,
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
}

/// Reads the `sensor_msgs/Imu` messages of `topic` (see [`BagReader::select_imu_topic`] for
/// the topic rules and the error that lists the bag's topics).
pub fn read_imu_series(path: &Path, topic: &str, opts: &ReadOptions) -> Result<ImuSeries, Error> {
    let bag = BagReader::open(path)?;
    let sel = bag.select_imu_topic(topic)?;
    // Indexed bags: every chunk decoded in parallel straight into its rows.
    if let Some(plan) = bag.chunk_plan(&sel)
        && let Some(s) = planned(&bag, &sel, &plan, opts.quiet)
    {
        return Ok(s);
    }
    let n = sel.expected as usize;
    let mut s = ImuSeries {
        topic: sel.topic.clone(),
        record_time: Vec::with_capacity(n),
        stamp: Vec::with_capacity(n),
        seq: Vec::with_capacity(n),
        acc: Vec::with_capacity(n),
        gyro: Vec::with_capacity(n),
        notes: Vec::new(),
    };
    let report = bag.stream_imu(&sel, opts.quiet, &mut |t, m| {
        s.record_time.push(t);
        s.stamp.push(m.stamp);
        s.seq.push(m.seq);
        s.acc.push(m.acc);
        s.gyro.push(m.gyro);
    })?;
    let StreamReport { order, notes, .. } = report;
    if let Some(order) = order {
        s.record_time = permute(&s.record_time, &order);
        s.stamp = permute(&s.stamp, &order);
        s.seq = permute(&s.seq, &order);
        s.acc = permute(&s.acc, &order);
        s.gyro = permute(&s.gyro, &order);
    }
    s.notes = notes;
    Ok(s)
}

/// One chunk's rows of every column.
struct Part<'a> {
    record_time: &'a mut [RosTime],
    stamp: &'a mut [RosTime],
    seq: &'a mut [u32],
    acc: &'a mut [[f64; 3]],
    gyro: &'a mut [[f64; 3]],
}

/// The parallel path of [`read_imu_series`]; `None` when a chunk does not match its index or
/// the record times are out of order (the streaming path handles both).
fn planned(
    bag: &BagReader,
    sel: &crate::bag::read::TopicSelection,
    plan: &[(u64, usize)],
    quiet: bool,
) -> Option<ImuSeries> {
    let n: usize = plan.iter().map(|(_, k)| k).sum();
    let mut s = ImuSeries {
        topic: sel.topic.clone(),
        record_time: vec![RosTime::default(); n],
        stamp: vec![RosTime::default(); n],
        seq: vec![0; n],
        acc: vec![[0.0; 3]; n],
        gyro: vec![[0.0; 3]; n],
        notes: bag.notes().to_vec(),
    };
    s.notes.extend(sel.note.iter().cloned());
    {
        let mut parts: Vec<Part> = BagReader::split_rows(&mut s.record_time, plan)
            .into_iter()
            .zip(BagReader::split_rows(&mut s.stamp, plan))
            .zip(BagReader::split_rows(&mut s.seq, plan))
            .zip(BagReader::split_rows(&mut s.acc, plan))
            .zip(BagReader::split_rows(&mut s.gyro, plan))
            .map(|((((record_time, stamp), seq), acc), gyro)| Part {
                record_time,
                stamp,
                seq,
                acc,
                gyro,
            })
            .collect();
        bag.decode_planned(sel, plan, &mut parts, quiet, |p, i, t, m| {
            p.record_time[i] = t;
            p.stamp[i] = m.stamp;
            p.seq[i] = m.seq;
            p.acc[i] = m.acc;
            p.gyro[i] = m.gyro;
        })
        .ok()?;
    }
    if s.record_time.windows(2).any(|w| w[1] < w[0]) {
        return None;
    }
    Some(s)
}

/// `v` reordered so that element `i` is `v[order[i]]`.
pub fn permute<T: Copy>(v: &[T], order: &[usize]) -> Vec<T> {
    order.iter().map(|&i| v[i]).collect()
}
