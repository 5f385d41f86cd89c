//! `bag2mat info BAG`: what an input holds, for any format — every topic with its type,
//! encoding, message count, nominal rate, rate jitter, time span and gaps (from the record
//! times of every message, by [`crate::timing`]'s rule), the Imu topics flagged and checked
//! as the analysers check them ([`crate::record_check`]: their findings under the topic),
//! and what the container reports lost.

use std::collections::BTreeMap;
use std::path::Path;

use rayon::prelude::*;

use crate::error::Error;
use crate::record_check::{self, Finding, Record};
use crate::series::is_imu;
use crate::source::{self, InputKind, Loss};
use crate::time::RosTime;

/// One topic (and type) of an input.
#[derive(Debug, Clone, PartialEq)]
pub struct TopicInfo {
    /// Topic name.
    pub topic: String,
    /// Message type.
    pub msg_type: String,
    /// Encoding (`ros1`, `cdr`, …).
    pub encoding: String,
    /// Whether the tools can read it as Imu.
    pub imu: bool,
    /// Messages read.
    pub count: u64,
    /// Messages the container promises, when it keeps a count.
    pub promised: Option<u64>,
    /// First and last record time, ns.
    pub span: Option<(u64, u64)>,
    /// Nominal rate of the record times (span over the sample periods it holds, so lost
    /// and duplicated messages do not change it), Hz; for an Imu topic, of the samples the
    /// analysers keep ([`crate::check_record`]).
    pub rate: Option<f64>,
    /// Median interval between consecutive messages, s.
    pub median_period: Option<f64>,
    /// Standard deviation of the intervals over their mean (relative jitter).
    pub jitter: Option<f64>,
    /// Gaps (intervals with at least one message missing), by [`crate::analyse_timing`]'s rule.
    pub gaps: u64,
    /// Messages missing in them.
    pub missing: u64,
    /// The longest interval, s.
    pub longest_gap: Option<f64>,
    /// What the record check finds on an Imu topic (record time), as the analysers do.
    pub findings: Vec<Finding>,
    /// Messages stamped before the log's own start ([`InfoReport::log_start`]), and the
    /// span of the others, ns.
    pub before_start: u64,
    /// First and last record time of the messages from the log's start on, ns.
    pub span_in_log: Option<(u64, u64)>,
    /// Why the analysers refuse the topic, when they do (integrated deltas far apart).
    pub refused: Option<String>,
}

/// What `bag2mat info` prints.
#[derive(Debug, Clone)]
pub struct InfoReport {
    /// What the input is.
    pub kind: InputKind,
    /// Every topic, sorted by name.
    pub topics: Vec<TopicInfo>,
    /// Notes from opening.
    pub notes: Vec<crate::shared::note::Note>,
    /// Data the container reports lost, and parts that could not be read.
    pub losses: Vec<Loss>,
    /// When the log itself says it started, ns (a PX4 ULog's header), if it says.
    pub log_start: Option<u64>,
}

/// Rate, median period, jitter, gaps, missing and longest interval of sorted times `t` (ns).
fn stats(t: &[i64]) -> (Option<f64>, Option<f64>, Option<f64>, u64, u64, Option<f64>) {
    if t.len() < 2 {
        return (None, None, None, 0, 0, None);
    }
    let d: Vec<f64> = t.windows(2).map(|w| (w[1] - w[0]) as f64 * 1e-9).collect();
    let mean = d.iter().sum::<f64>() / d.len() as f64;
    let var = d.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / d.len() as f64;
    let jitter = (mean > 0.0).then(|| var.sqrt() / mean);
    let longest = d.iter().cloned().fold(0.0, f64::max);
    // Gaps are found where the analysers find them.
    let tm = crate::timing::analyse(t);
    (
        tm.nominal_rate(),
        tm.median_period_ns.map(|p| p as f64 * 1e-9),
        jitter,
        tm.gaps.len() as u64,
        tm.missing,
        Some(longest),
    )
}

/// Reads every message's record time of `path` and summarises each topic; the Imu topics
/// are read whole and checked as the analysers check them.
pub fn info(path: &Path, quiet: bool) -> Result<InfoReport, Error> {
    info_with(path, quiet, &crate::formats::InputOptions::default())
}

/// [`info`], with what the user said about a log whose content does not say it all.
pub fn info_with(
    path: &Path,
    quiet: bool,
    opts: &crate::formats::InputOptions,
) -> Result<InfoReport, Error> {
    let src = crate::input::open_with(path, opts)?;
    let (times, losses) = read_times(src.as_ref(), quiet);
    let log_start = src.contents().log_start;
    let mut by = topic_infos(src.as_ref(), times, log_start);
    check_imu_topics(src.as_ref(), &mut by);
    Ok(InfoReport {
        kind: src.kind(),
        topics: by.into_values().collect(),
        notes: src.notes().to_vec(),
        losses,
        log_start,
    })
}

/// Every message's record time per channel, read part by part in parallel, and every loss
/// the container and its parts report.
fn read_times(src: &dyn source::Source, quiet: bool) -> (BTreeMap<u32, Vec<u64>>, Vec<Loss>) {
    let parts = src.parts();
    let pb = crate::shared::progress::bar(parts.len().max(1) as u64, quiet, "parts");
    pb.set_message("reading");
    let per_part: Vec<(BTreeMap<u32, Vec<u64>>, source::PartRead)> = (0..parts.len())
        .into_par_iter()
        .map(|i| {
            let mut m: BTreeMap<u32, Vec<u64>> = BTreeMap::new();
            let r = src.read_part(i, &|_| true, &mut |c, t, _| m.entry(c).or_default().push(t));
            pb.inc(1);
            (m, r)
        })
        .collect();
    pb.finish_and_clear();
    let mut losses: Vec<Loss> = src.losses().to_vec();
    let mut times: BTreeMap<u32, Vec<u64>> = BTreeMap::new();
    for (i, (m, r)) in per_part.into_iter().enumerate() {
        losses.extend(r.lost);
        let why = (r.error.as_ref().map(|e| e.to_string()))
            .or_else(|| r.skip_reason.as_ref().map(|s| s.to_string()));
        if let Some(e) = why {
            losses.push(Loss {
                what: format!("{}: {e}", parts[i].label),
                messages: None,
                span: parts[i].span,
                channel: None,
                ..Loss::default()
            });
        }
        for (c, v) in m {
            times.entry(c).or_default().extend(v);
        }
    }
    losses.extend(src.losses_after_read());
    (times, losses)
}

/// One entry per topic and type: its channels' promised counts, and its record times'
/// count, span, rate and gaps (and which of them precede the log's own start).
fn topic_infos(
    src: &dyn source::Source,
    mut times: BTreeMap<u32, Vec<u64>>,
    log_start: Option<u64>,
) -> BTreeMap<(String, String), TopicInfo> {
    let mut by: BTreeMap<(String, String), TopicInfo> = BTreeMap::new();
    let mut topic_times: BTreeMap<(String, String), Vec<u64>> = BTreeMap::new();
    for c in src.channels() {
        let key = (c.topic.clone(), c.msg_type.clone());
        let e = by.entry(key.clone()).or_insert_with(|| TopicInfo::empty(c));
        e.imu &= is_imu(c);
        e.promised = e.promised.zip(c.count).map(|(a, b)| a + b);
        topic_times
            .entry(key)
            .or_default()
            .extend(times.remove(&c.id).unwrap_or_default());
    }
    for (key, mut t) in topic_times {
        let e = by.get_mut(&key).expect("same keys");
        e.count = t.len() as u64;
        t.sort_unstable();
        let ns: Vec<i64> = t.iter().map(|&x| x as i64).collect();
        let (rate, median, jitter, gaps, missing, longest) = stats(&ns);
        e.span = t.first().zip(t.last()).map(|(a, b)| (*a, *b));
        let early = log_start.map_or(0, |s| t.partition_point(|&x| x < s));
        e.before_start = early as u64;
        e.span_in_log = t[early..].first().zip(t.last()).map(|(a, b)| (*a, *b));
        e.rate = rate;
        e.median_period = median;
        e.jitter = jitter;
        e.gaps = gaps;
        e.missing = missing;
        e.longest_gap = longest;
    }
    by
}

impl TopicInfo {
    /// The entry of channel `c`'s topic before any of its messages is counted.
    fn empty(c: &source::Channel) -> TopicInfo {
        TopicInfo {
            topic: c.topic.clone(),
            msg_type: c.msg_type.clone(),
            encoding: c.encoding.name().to_string(),
            imu: true,
            count: 0,
            promised: Some(0),
            span: None,
            rate: None,
            median_period: None,
            jitter: None,
            gaps: 0,
            missing: 0,
            longest_gap: None,
            findings: Vec::new(),
            before_start: 0,
            span_in_log: None,
            refused: None,
        }
    }
}

/// The record check of every Imu topic on its record time, as `allan_kalibr` runs it: its
/// findings, and the rate and gaps of the samples it keeps.
fn check_imu_topics(src: &dyn source::Source, by: &mut BTreeMap<(String, String), TopicInfo>) {
    let sel = crate::TopicSelector {
        topics: Vec::new(),
        all_imu: true,
        preferred: None,
    };
    // a topic that cannot be read as Imu keeps its plain summary (the read says why)
    let Ok(read) = crate::series::read_from(src, &sel, &crate::ReadOptions { quiet: true }) else {
        return;
    };
    for s in &read.series {
        let Some(e) = by.get_mut(&(s.topic.clone(), s.msg_type.clone())) else {
            continue;
        };
        let t = crate::timing::ns_of_times(&s.record_time);
        let other = crate::timing::ns_of_times(&s.stamp);
        let rec = Record::of_series(s, crate::TimeColumn::Record, &t, &other);
        let c = record_check::check(&rec, &record_check::Options::default());
        // the rate of what the analysers keep; the gaps and missing samples stay the whole
        // topic's, as its findings count them (a record cut to its longest stretch has none
        // left in it, but they are the topic's)
        e.rate = c.rate;
        e.refused = s.check_integration().err().map(|e| e.to_string());
        e.findings = c.findings;
        if e.refused.is_some() {
            // rows that are no samples say nothing of the sensor through the checks that
            // read values as samples (a noise density read at the rows' spacing came out
            // as "deg/s read as rad/s?"): the refusal says what they are
            e.findings.retain(|f| !f.kind.judges_values_as_samples());
        }
    }
}

impl InfoReport {
    /// The printed report.
    pub fn text(&self, path: &Path) -> String {
        let mut s = format!(
            "path:      {}\nformat:    {}\n",
            path.display(),
            self.kind.describe()
        );
        // the log's own span: a message its logger wrote from before it started (a
        // topic's last message at subscription) is listed with its topic, not spanned
        let spans: Vec<(u64, u64)> = self.topics.iter().filter_map(|t| t.span_in_log).collect();
        if let (Some(a), Some(b)) = (
            spans.iter().map(|x| x.0).min(),
            spans.iter().map(|x| x.1).max(),
        ) {
            s.push_str(&format!(
                "start:     {}\nend:       {}\nduration:  {:.3} s\n",
                RosTime::from_nanos(a),
                RosTime::from_nanos(b),
                (b - a) as f64 * 1e-9
            ));
        }
        let total: u64 = self.topics.iter().map(|t| t.count).sum();
        s.push_str(&format!(
            "messages:  {total}\ntopics:    {}   (* = sensor_msgs/Imu, read by the tools)\n",
            self.topics.len()
        ));
        s.push_str(&format!(
            "  {:<28} {:<22} {:>5} {:>9} {:>11} {:>8} {:>11} {:>5} {:>8} {:>10}\n",
            "topic",
            "type",
            "enc",
            "msgs",
            "rate Hz",
            "jitter",
            "span s",
            "gaps",
            "missing",
            "longest s"
        ));
        let opt =
            |v: Option<f64>, p: usize| v.map(|x| format!("{x:.p$}")).unwrap_or_else(|| "-".into());
        for t in &self.topics {
            s.push_str(&format!(
                "{} {:<28} {:<22} {:>5} {:>9} {:>11} {:>8} {:>11} {:>5} {:>8} {:>10}\n",
                if t.imu { "*" } else { " " },
                crate::printable::escape(&t.topic),
                crate::printable::escape(&t.msg_type),
                t.encoding,
                t.count,
                opt(t.rate, 3),
                t.jitter
                    .map(|j| format!("{:.2}%", j * 100.0))
                    .unwrap_or_else(|| "-".into()),
                opt(t.span.map(|(a, b)| (b - a) as f64 * 1e-9), 3),
                t.gaps,
                t.missing,
                opt(t.longest_gap, 4),
            ));
            if let Some(r) = &t.refused {
                s.push_str(&format!("    warning: the analysers refuse it: {r}\n"));
            }
            for f in &t.findings {
                s.push_str(&format!("    {f}\n"));
            }
            if let Some(p) = t.promised
                && p != t.count
            {
                s.push_str(&format!(
                    "    the container promises {p} messages on this topic, {} were read\n",
                    t.count
                ));
            }
        }
        for n in &self.notes {
            s.push_str(&format!("note: {}\n", n.text));
        }
        if let Some(start) = self.log_start {
            for t in self.topics.iter().filter(|t| t.before_start > 0) {
                let first = t.span.map_or(start, |s| s.0);
                s.push_str(&format!(
                    "note: {} message{} of '{}' {} stamped before the log started (the first {:.3} s before it: the logger writes each topic's latest message when it starts): listed with the topic, left out of the duration\n",
                    t.before_start,
                    if t.before_start == 1 { "" } else { "s" },
                    crate::printable::escape(&t.topic),
                    if t.before_start == 1 { "is" } else { "are" },
                    start.saturating_sub(first) as f64 * 1e-9
                ));
            }
        }
        for l in &self.losses {
            s.push_str(&format!("lost: {l}\n"));
        }
        s
    }
}
