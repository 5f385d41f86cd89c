//! The rows of a read: one decoded sample ([`Row`], also the fixed payload of the log
//! readers' channels), the columns of a topic ([`Rows`]: one row per message, in
//! record-time order) and the mutable views the parallel decode writes each part into
//! ([`RowsMut`]). Below the readers and the read path, which all write them.

use crate::error::Error;
use crate::imu_msg::ImuSample;
use crate::time::RosTime;

/// Bytes of one [`Row`] payload: the sample time (u64 ns), then acc x y z and gyro x y z
/// (f64), little-endian.
pub const ROW_LEN: usize = 56;

/// One decoded sample. A sensor a topic does not carry (a gyro-only topic's accelerometer)
/// is NaN.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Row {
    /// The sensor's sample time, ns (`header.stamp` of the series).
    pub stamp: u64,
    /// Linear acceleration, m/s².
    pub acc: [f64; 3],
    /// Angular velocity, rad/s.
    pub gyro: [f64; 3],
}

impl Row {
    /// The payload.
    pub(crate) fn encode(&self) -> [u8; ROW_LEN] {
        let mut b = [0u8; ROW_LEN];
        b[..8].copy_from_slice(&self.stamp.to_le_bytes());
        for (i, v) in self.acc.iter().chain(&self.gyro).enumerate() {
            b[8 + 8 * i..16 + 8 * i].copy_from_slice(&v.to_le_bytes());
        }
        b
    }

    /// The sample of a payload.
    pub(crate) fn decode(b: &[u8]) -> Result<ImuSample, Error> {
        let Some(b) = b.first_chunk::<ROW_LEN>().filter(|_| b.len() == ROW_LEN) else {
            return Err(Error::BadMessage {
                what: format!("a decoded row is {ROW_LEN} bytes, this one {}", b.len()),
            });
        };
        let (stamp, values) = b.split_first_chunk::<8>().unwrap_or((&[0; 8], &[]));
        let mut v = [0f64; 6];
        for (x, c) in v.iter_mut().zip(values.chunks_exact(8)) {
            *x = f64::from_le_bytes(c.try_into().unwrap_or([0; 8]));
        }
        Ok(ImuSample::from(&Row {
            stamp: u64::from_le_bytes(*stamp),
            acc: [v[0], v[1], v[2]],
            gyro: [v[3], v[4], v[5]],
        }))
    }
}

impl From<&Row> for ImuSample {
    fn from(r: &Row) -> ImuSample {
        ImuSample {
            seq: 0,
            stamp: RosTime::from_nanos(r.stamp),
            acc: r.acc,
            gyro: r.gyro,
        }
    }
}

/// The columns of one topic's rows, as [`crate::ImuSeries`] holds them (what a log reader that
/// decoded a topic on opening hands over whole: [`crate::source::Source::take_rows`]).
#[derive(Debug, Clone, Default)]
pub struct Rows {
    pub(crate) record_time: Vec<RosTime>,
    pub(crate) stamp: Vec<RosTime>,
    pub(crate) seq: Vec<u32>,
    pub(crate) acc: [Vec<f64>; 3],
    pub(crate) gyro: [Vec<f64>; 3],
}

impl Rows {
    /// `n` rows of zeros (allocated zeroed: pages are touched only where written, by the
    /// parallel readers; `vec![RosTime::default(); n]` would write the times serially).
    pub(crate) fn zeroed(n: usize) -> Rows {
        Rows {
            record_time: bytemuck::zeroed_vec(n),
            stamp: bytemuck::zeroed_vec(n),
            seq: vec![0; n],
            acc: std::array::from_fn(|_| vec![0.0; n]),
            gyro: std::array::from_fn(|_| vec![0.0; n]),
        }
    }

    pub(crate) fn len(&self) -> usize {
        self.record_time.len()
    }

    /// Room for `n` more rows.
    pub(crate) fn reserve(&mut self, n: usize) {
        self.record_time.reserve(n);
        self.stamp.reserve(n);
        self.seq.reserve(n);
        for c in 0..3 {
            self.acc[c].reserve(n);
            self.gyro[c].reserve(n);
        }
    }

    /// Appends a decoded row logged at `t` ns.
    pub(crate) fn push_row(&mut self, t: u64, r: &Row) {
        self.push(t, &ImuSample::from(r));
    }

    /// Row `i` as a decoded row.
    pub(crate) fn row(&self, i: usize) -> Row {
        Row {
            stamp: self.stamp[i].as_nanos(),
            acc: std::array::from_fn(|c| self.acc[c][i]),
            gyro: std::array::from_fn(|c| self.gyro[c][i]),
        }
    }

    /// Keeps the first `n` rows.
    pub(crate) fn truncate(&mut self, n: usize) {
        self.record_time.truncate(n);
        self.stamp.truncate(n);
        self.seq.truncate(n);
        for c in 0..3 {
            self.acc[c].truncate(n);
            self.gyro[c].truncate(n);
        }
    }

    /// Moves rows `from..from + n` to `to` (`to <= from`).
    pub(crate) fn move_down(&mut self, from: usize, n: usize, to: usize) {
        let r = from..from + n;
        self.record_time.copy_within(r.clone(), to);
        self.stamp.copy_within(r.clone(), to);
        self.seq.copy_within(r.clone(), to);
        for c in 0..3 {
            self.acc[c].copy_within(r.clone(), to);
            self.gyro[c].copy_within(r.clone(), to);
        }
    }

    pub(crate) fn push(&mut self, t: u64, s: &ImuSample) {
        self.record_time.push(RosTime::from_nanos(t));
        self.stamp.push(s.stamp);
        self.seq.push(s.seq);
        for c in 0..3 {
            self.acc[c].push(s.acc[c]);
            self.gyro[c].push(s.gyro[c]);
        }
    }

    /// Appends rows `..n` of `slot`.
    pub(crate) fn extend_from(&mut self, slot: &RowsMut<'_>, n: usize) {
        self.record_time.extend_from_slice(&slot.record_time[..n]);
        self.stamp.extend_from_slice(&slot.stamp[..n]);
        self.seq.extend_from_slice(&slot.seq[..n]);
        for c in 0..3 {
            self.acc[c].extend_from_slice(&slot.acc[c][..n]);
            self.gyro[c].extend_from_slice(&slot.gyro[c][..n]);
        }
    }

    pub(crate) fn append(&mut self, other: &Rows) {
        self.record_time.extend_from_slice(&other.record_time);
        self.stamp.extend_from_slice(&other.stamp);
        self.seq.extend_from_slice(&other.seq);
        for c in 0..3 {
            self.acc[c].extend_from_slice(&other.acc[c]);
            self.gyro[c].extend_from_slice(&other.gyro[c]);
        }
    }

    /// One mutable slot per part, of the given lengths.
    pub(crate) fn split(&mut self, sizes: &[usize]) -> Vec<RowsMut<'_>> {
        let mut rt = split_rows(&mut self.record_time, sizes).into_iter();
        let mut st = split_rows(&mut self.stamp, sizes).into_iter();
        let mut sq = split_rows(&mut self.seq, sizes).into_iter();
        let [a0, a1, a2] = &mut self.acc;
        let [g0, g1, g2] = &mut self.gyro;
        let mut cols: [std::vec::IntoIter<&mut [f64]>; 6] = [
            split_rows(a0, sizes).into_iter(),
            split_rows(a1, sizes).into_iter(),
            split_rows(a2, sizes).into_iter(),
            split_rows(g0, sizes).into_iter(),
            split_rows(g1, sizes).into_iter(),
            split_rows(g2, sizes).into_iter(),
        ];
        (0..sizes.len())
            .map(|_| {
                let mut col = |j: usize| cols[j].next().unwrap_or_default();
                RowsMut {
                    acc: [col(0), col(1), col(2)],
                    gyro: [col(3), col(4), col(5)],
                    record_time: rt.next().unwrap_or_default(),
                    stamp: st.next().unwrap_or_default(),
                    seq: sq.next().unwrap_or_default(),
                }
            })
            .collect()
    }

    /// Sorts by record time (stable) when the storage order differs from it; returns the
    /// storage position of each row if it did.
    pub(crate) fn sort_by_record_time(&mut self) -> Option<Vec<u32>> {
        if !self.record_time.windows(2).any(|w| w[1] < w[0]) {
            return None;
        }
        let mut order: Vec<usize> = (0..self.len()).collect();
        order.sort_by_key(|&i| self.record_time[i]);
        self.record_time = permute(&self.record_time, &order);
        self.stamp = permute(&self.stamp, &order);
        self.seq = permute(&self.seq, &order);
        for c in 0..3 {
            self.acc[c] = permute(&self.acc[c], &order);
            self.gyro[c] = permute(&self.gyro[c], &order);
        }
        Some(order.into_iter().map(|i| i as u32).collect())
    }
}

/// One part's rows of every column of one topic.
#[derive(Default)]
pub(crate) struct RowsMut<'a> {
    pub(crate) record_time: &'a mut [RosTime],
    pub(crate) stamp: &'a mut [RosTime],
    pub(crate) seq: &'a mut [u32],
    pub(crate) acc: [&'a mut [f64]; 3],
    pub(crate) gyro: [&'a mut [f64]; 3],
}

impl RowsMut<'_> {
    pub(crate) fn cap(&self) -> usize {
        self.record_time.len()
    }

    /// Sets row `i` to a decoded row logged at `t` ns (its seq stays 0).
    #[inline]
    pub(crate) fn set_row(&mut self, i: usize, t: u64, r: &Row) {
        self.record_time[i] = RosTime::from_nanos(t);
        self.stamp[i] = RosTime::from_nanos(r.stamp);
        for c in 0..3 {
            self.acc[c][i] = r.acc[c];
            self.gyro[c][i] = r.gyro[c];
        }
    }

    pub(crate) fn set(&mut self, i: usize, t: u64, s: &ImuSample) {
        self.record_time[i] = RosTime::from_nanos(t);
        self.stamp[i] = s.stamp;
        self.seq[i] = s.seq;
        for c in 0..3 {
            self.acc[c][i] = s.acc[c];
            self.gyro[c][i] = s.gyro[c];
        }
    }
}

/// Splits a column into one slice per part, of the given lengths.
pub(crate) fn split_rows<'a, T>(column: &'a mut [T], sizes: &[usize]) -> Vec<&'a mut [T]> {
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

/// `v` reordered so that element `i` is `v[order[i]]`.
pub fn permute<T: Copy>(v: &[T], order: &[usize]) -> Vec<T> {
    order.iter().map(|&i| v[i]).collect()
}
