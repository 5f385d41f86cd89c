//! The high-rate batch sampler's messages (`ISBH` headers, `ISBD` data) put together once the
//! whole log is read, so that each damaged field can be judged against the log's other
//! batches: ArduPilot writes every batch of a sensor with the same sample count, multiplier
//! and rate, and a batch's `ISBD` messages in sequence right after its header. A data message
//! whose batch number or sequence number is damaged joins the batch its place in the file
//! says; a header whose sensor type or instance is damaged joins the sensor whose multiplier
//! it has; a damaged sample count, multiplier or rate is read as the sensor's usual one. What
//! no message holds any more is counted per sensor: the samples a batch lacks against the
//! sensor's usual count.

use std::collections::HashMap;

use super::{Def, ISBD_SAMPLES};
use crate::rows::Row;

/// An `ISBH` header as read.
#[derive(Debug, Clone)]
pub(super) struct Header {
    at: usize,
    n: u16,
    kind: u8,
    inst: u32,
    mul: f64,
    count: u64,
    start_us: u64,
    rate: f64,
}

/// An `ISBD` data message as read: its batch and sequence numbers and its samples.
#[derive(Debug, Clone)]
pub(super) struct Data {
    at: usize,
    n: u16,
    seq: u16,
    xyz: [[i16; ISBD_SAMPLES]; 3],
    /// Samples whose three values the message holds (all but in one cut short).
    held: usize,
}

/// A sensor's batches: (`type`, instance).
pub(super) type Key = (u8, u32);

/// What the batches gave: each sensor's samples (record time = stamp, ns; the row), and
/// what was repaired or lost.
#[derive(Default)]
pub(super) struct Batches {
    headers: Vec<Header>,
    datas: Vec<Data>,
    /// Per sensor, its samples in file order.
    pub(super) samples: Vec<(Key, Vec<(u64, Row)>)>,
    /// Samples lost per sensor: (count, batches short).
    pub(super) lost: HashMap<Key, (u64, u64)>,
    /// Samples a sensor's last batch lacks (the log may have stopped before writing them):
    /// (count, first offset).
    pub(super) unfinished: HashMap<Key, (u64, usize)>,
    /// Data messages that belong to no batch: count (their 32 samples each may be any
    /// sensor's).
    pub(super) orphans: u64,
    /// Repairs by kind: (count, first offset).
    pub(super) repaired: Vec<(&'static str, u64, usize)>,
}

fn repaired(r: &mut Vec<(&'static str, u64, usize)>, what: &'static str, at: usize) {
    match r.iter_mut().find(|x| x.0 == what) {
        Some(x) => x.1 += 1,
        None => r.push((what, 1, at)),
    }
}

/// The most common value (ties: the first seen), when at least two agree.
fn mode<T: PartialEq + Copy>(v: &[T]) -> Option<T> {
    let mut best: Option<(T, usize)> = None;
    for (i, x) in v.iter().enumerate() {
        if v[..i].contains(x) {
            continue;
        }
        let n = v.iter().filter(|y| *y == x).count();
        if best.is_none_or(|(_, b)| n > b) {
            best = Some((*x, n));
        }
    }
    best.filter(|(_, n)| *n >= 2).map(|(x, _)| x)
}

impl Batches {
    /// An `ISBH` message at `at`.
    pub(super) fn header(&mut self, d: &Def, p: &[u8], at: usize) {
        let h = (|| {
            Some(Header {
                at,
                n: d.get(p, "N")? as u16,
                kind: d.get(p, "type")? as u8,
                inst: d.get(p, "instance")? as u32,
                mul: d.get(p, "mul")?,
                count: d.get(p, "smp_cnt")? as u64,
                start_us: d.get_u64(p, "SampleUS")?,
                rate: d.get(p, "smp_rate")?,
            })
        })();
        if let Some(h) = h {
            self.headers.push(h);
        }
    }

    /// An `ISBD` message at `at`.
    pub(super) fn data(&mut self, d: &Def, p: &[u8], at: usize) {
        let (Some(n), Some(seq)) = (d.get(p, "N"), d.get(p, "seqno")) else {
            return;
        };
        let (Some(x), Some(y), Some(z)) = (d.array(p, "x"), d.array(p, "y"), d.array(p, "z"))
        else {
            // a message cut before its samples: its batch counts them
            return;
        };
        self.datas.push(Data {
            at,
            n: n as u16,
            seq: seq as u16,
            held: x.1.min(y.1).min(z.1),
            xyz: [x.0, y.0, z.0],
        });
    }

    /// Every batch put together: headers repaired against their sensor's others, data
    /// joined to their batch, samples expanded, shortfalls counted.
    pub(super) fn finish(&mut self) {
        self.repair_headers();
        let groups = self.join();
        let keys: Vec<Key> = self.headers.iter().map(|h| (h.kind, h.inst)).collect();
        let usual = |key: Key, f: fn(&Header) -> u64| -> Option<u64> {
            let v: Vec<u64> = self
                .headers
                .iter()
                .zip(&keys)
                .filter(|(_, k)| **k == key)
                .map(|(h, _)| f(h))
                .collect();
            mode(&v)
        };
        let mut out: Vec<(Key, Vec<(u64, Row)>)> = Vec::new();
        for (hi, datas) in groups.iter().enumerate() {
            let h = self.headers[hi].clone();
            let key = (h.kind, h.inst);
            if !matches!(h.kind, 0 | 1) {
                // a sensor no other batch says: its samples may be any sensor's
                self.orphans += datas.len() as u64;
                continue;
            }
            let mul = if h.mul > 0.0 && h.mul.is_finite() {
                h.mul
            } else if let Some(m) = usual(key, |h| h.mul.to_bits()).map(f64::from_bits) {
                repaired(
                    &mut self.repaired,
                    "a batch's damaged multiplier read as its sensor's usual one",
                    h.at,
                );
                m
            } else {
                0.0
            };
            let rate = if h.rate > 0.0 && h.rate.is_finite() {
                h.rate
            } else if let Some(r) = usual(key, |h| h.rate.to_bits()).map(f64::from_bits) {
                repaired(
                    &mut self.repaired,
                    "a batch's damaged rate read as its sensor's usual one",
                    h.at,
                );
                r
            } else {
                0.0
            };
            // the sensor's usual count; the header's own where the sensor has no other batch
            let expected = match usual(key, |h| h.count) {
                Some(c) => {
                    if c != h.count {
                        repaired(
                            &mut self.repaired,
                            "a batch whose header's sample count differs from its sensor's others read by its data",
                            h.at,
                        );
                    }
                    c
                }
                None => h.count.max(datas.len() as u64 * ISBD_SAMPLES as u64),
            };
            if !(mul > 0.0 && rate > 0.0) {
                let e = self.lost.entry(key).or_default();
                e.0 += expected;
                e.1 += 1;
                continue;
            }
            let mut got = 0u64;
            let idx = match out.iter().position(|(k, _)| *k == key) {
                Some(i) => i,
                None => {
                    out.push((key, Vec::new()));
                    out.len() - 1
                }
            };
            for (seq, di) in datas {
                let xyz = &self.datas[*di].xyz;
                for k in 0..self.datas[*di].held {
                    let j = *seq as u64 * ISBD_SAMPLES as u64 + k as u64;
                    if j >= expected {
                        break;
                    }
                    let t = h
                        .start_us
                        .saturating_mul(1000)
                        .saturating_add((j as f64 * 1e9 / rate).round() as u64);
                    let v = xyz.map(|c| c[k] as f64 / mul);
                    let nan = [f64::NAN; 3];
                    let (gyro, acc) = if h.kind == 1 { (v, nan) } else { (nan, v) };
                    out[idx].1.push((
                        t,
                        Row {
                            stamp: t,
                            gyro,
                            acc,
                        },
                    ));
                    got += 1;
                }
            }
            if got < expected {
                let last = !self.headers[hi + 1..]
                    .iter()
                    .any(|x| (x.kind, x.inst) == key);
                if last {
                    self.unfinished.insert(key, (expected - got, h.at));
                } else {
                    let e = self.lost.entry(key).or_default();
                    e.0 += expected - got;
                    e.1 += 1;
                }
            }
        }
        self.samples = out;
    }

    /// Headers whose sensor type is none of the two, or whose (type, instance) no other
    /// batch has, moved to the sensor whose multiplier they carry (when one sensor has it).
    fn repair_headers(&mut self) {
        let keys: Vec<Key> = self.headers.iter().map(|h| (h.kind, h.inst)).collect();
        let count = |k: Key| keys.iter().filter(|x| **x == k).count();
        let muls: Vec<u64> = self.headers.iter().map(|h| h.mul.to_bits()).collect();
        let usual_mul = |k: Key| {
            let v: Vec<u64> = keys
                .iter()
                .zip(&muls)
                .filter(|(x, _)| **x == k)
                .map(|(_, m)| *m)
                .collect();
            mode(&v)
        };
        for i in 0..self.headers.len() {
            let k = keys[i];
            let mul = muls[i];
            let odd = !matches!(k.0, 0 | 1)
                || (count(k) == 1 && keys.iter().any(|x| count(*x) > 1))
                || usual_mul(k).is_some_and(|m| m != mul);
            if !odd {
                continue;
            }
            let mut fits: Vec<Key> = keys
                .iter()
                .filter(|x| {
                    **x != k
                        && matches!(x.0, 0 | 1)
                        && count(**x) > 1
                        && usual_mul(**x) == Some(mul)
                })
                .copied()
                .collect();
            fits.sort_unstable();
            fits.dedup();
            if let [to] = fits[..] {
                let h = &mut self.headers[i];
                (h.kind, h.inst) = to;
                repaired(
                    &mut self.repaired,
                    "a batch whose header's sensor type or instance is damaged joined the sensor whose multiplier it carries",
                    h.at,
                );
            }
        }
    }

    /// A batch's sequence numbers in file order (ArduPilot writes them counting up): one
    /// that breaks the count where its neighbours keep it is the one between them, the
    /// first is 0 when the second is 1, a repeated last one follows the one before.
    fn fix_sequence(&mut self, g: &mut [(u16, usize)]) {
        let n = g.len();
        for i in 0..n {
            let prev = if i == 0 {
                None
            } else {
                Some(g[i - 1].0 as u32)
            };
            let want = prev.map_or(0, |p| p + 1);
            if g[i].0 as u32 == want {
                continue;
            }
            let next = g.get(i + 1).map(|x| x.0 as u32);
            let between = match (prev, next) {
                (_, Some(nx)) => nx == want + 1,
                (Some(_), None) => {
                    g[..i].iter().any(|x| x.0 == g[i].0) || g[i].0 as u32 > want + 64
                }
                (None, None) => false,
            };
            if between && want <= u16::MAX as u32 {
                g[i].0 = want as u16;
                let at = self.datas[g[i].1].at;
                repaired(
                    &mut self.repaired,
                    "a batch data message with a damaged sequence number read as the one its neighbours leave",
                    at,
                );
            }
        }
    }

    /// Each header's data messages with their sequence numbers, in file order: a data
    /// message joins the batch its number names when it continues it, else the batch of the
    /// data message before it when it continues that one (a damaged batch number); a
    /// sequence number out of its batch's order is the next one (damaged).
    fn join(&mut self) -> Vec<Vec<(u16, usize)>> {
        let mut groups: Vec<Vec<(u16, usize)>> = vec![Vec::new(); self.headers.len()];
        let (mut h, mut d) = (0usize, 0usize);
        let mut open: HashMap<u16, usize> = HashMap::new();
        let mut last: Option<usize> = None;
        // headers and data in file order
        while h < self.headers.len() || d < self.datas.len() {
            if h < self.headers.len()
                && (d >= self.datas.len() || self.headers[h].at < self.datas[d].at)
            {
                open.insert(self.headers[h].n, h);
                last = None;
                h += 1;
                continue;
            }
            let x = &self.datas[d];
            let next_of = |g: &Vec<(u16, usize)>| g.last().map_or(0, |l| l.0 as u32 + 1);
            let claimed = open.get(&x.n).copied();
            let continues = |b: usize| x.seq as u32 == next_of(&groups[b]);
            let target = match (claimed, last) {
                (Some(c), _) if continues(c) => Some(c),
                (_, Some(l)) if continues(l) => {
                    repaired(
                        &mut self.repaired,
                        "a batch data message with a damaged batch number joined the batch it continues",
                        x.at,
                    );
                    Some(l)
                }
                (Some(c), _) => Some(c),
                (None, Some(l)) => {
                    repaired(
                        &mut self.repaired,
                        "a batch data message with a damaged batch number joined the batch it continues",
                        x.at,
                    );
                    Some(l)
                }
                (None, None) => None,
            };
            match target {
                Some(b) => {
                    groups[b].push((x.seq, d));
                    last = Some(b);
                }
                None => self.orphans += 1,
            }
            d += 1;
        }
        for g in &mut groups {
            self.fix_sequence(g);
        }
        groups
    }
}
