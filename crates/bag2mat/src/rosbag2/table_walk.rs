//! The rows of one stretch of a rosbag2 `messages` table in the order SQLite's b-tree holds
//! them, checked against the rule every rosbag2 writer follows: row ids 1, 2, 3, … without
//! gaps, in id order.
//!
//! A damaged page breaks that order in ways SQLite itself does not notice: a damaged row id
//! puts a row out of place (a range scan stops there), a lowered cell count hides rows, a
//! damaged child pointer hides a page or shows one twice. The reader therefore walks the
//! table's leaves in order (never an index, never an id range with an upper bound), records
//! the walk as runs of consecutive ids, and this module decides from the runs alone:
//!
//! * the **backbone**: the heaviest chain of runs in increasing id order (what the table
//!   holds in place);
//! * each **hole** between backbone runs: the ids the table should hold there, the rows
//!   found out of place inside it (a row whose id is damaged sits where its real id
//!   belongs: it fills the hole and is delivered), and what is left: rows lost, with the
//!   record times of the rows around them;
//! * **doubles**: out-of-place rows that repeat a row of the backbone (same id, same
//!   record time: a page reached twice), or that no hole has room for, are not delivered
//!   again.

/// Consecutive ids met one after the other in the walk.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Run {
    /// The first id.
    pub first: i64,
    /// Rows in the run.
    pub len: u64,
    /// Record time of its first and last row.
    pub ts_first: i64,
    /// Record time of its last row.
    pub ts_last: i64,
}

impl Run {
    /// Its last id.
    pub(crate) fn last(&self) -> i64 {
        self.first.saturating_add(self.len as i64 - 1)
    }
}

/// A stretch of the walk SQLite read without an error, from a sought id.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Segment {
    /// The id the stretch was sought from (`id >= seek`).
    pub seek: i64,
    /// Rows read before it ended.
    pub rows: u64,
    /// Why it ended early (SQLite's error), if it did.
    pub error: Option<String>,
}

/// A walk: runs in walk order and the segments that read them.
#[derive(Debug, Clone, Default)]
pub(crate) struct Walk {
    /// Runs of consecutive ids, in walk order.
    pub runs: Vec<Run>,
    /// The stretches read, in order; their rows add up to the runs'.
    pub segments: Vec<Segment>,
}

impl Walk {
    /// Appends the next row of the walk.
    pub(crate) fn push(&mut self, id: i64, ts: i64) {
        if let Some(r) = self.runs.last_mut()
            && r.last().checked_add(1) == Some(id)
        {
            r.len += 1;
            r.ts_last = ts;
            return;
        }
        self.runs.push(Run {
            first: id,
            len: 1,
            ts_first: ts,
            ts_last: ts,
        });
    }

    /// Rows walked.
    pub(crate) fn rows(&self) -> u64 {
        self.runs.iter().map(|r| r.len).sum()
    }
}

/// Ids the table should hold between two rows it holds in place, and what became of them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Hole {
    /// The first and last id of the hole.
    pub ids: (i64, i64),
    /// Rows lost: the hole's size less the out-of-place rows that filled it.
    pub lost: u64,
    /// Record times of the rows around it (before, after), when the walk holds them.
    pub around: (Option<i64>, Option<i64>),
    /// SQLite's error, when the walk broke inside the hole.
    pub error: Option<String>,
}

/// What to deliver of a walk, and what it lost.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct Plan {
    /// Walk positions `a..b` not to deliver (doubles), in order.
    pub skip: Vec<(u64, u64)>,
    /// Holes with rows lost.
    pub holes: Vec<Hole>,
    /// Out-of-place rows delivered in a hole (rows whose id is damaged), with the first
    /// such id.
    pub moved: (u64, Option<i64>),
    /// Rows not delivered because they repeat others.
    pub doubles: u64,
    /// The highest id the backbone holds, with its record time.
    pub max_id: Option<(i64, i64)>,
    /// The lowest id the backbone holds.
    pub min_id: Option<i64>,
}

/// The heaviest chain (by rows) of runs with increasing ids, each inside `lo..hi`, in walk
/// order: indices into `runs`.
fn backbone(runs: &[Run], lo: i64, hi: i64) -> Vec<usize> {
    let elig: Vec<usize> = (0..runs.len())
        .filter(|&i| runs[i].first >= lo && runs[i].last() < hi)
        .collect();
    if elig
        .windows(2)
        .all(|w| runs[w[0]].last() < runs[w[1]].first)
    {
        return elig;
    }
    // Weighted longest increasing chain: a Fenwick tree of (best weight, chain end) over
    // the runs' last ids, queried for the best chain ending below a run's first id.
    let mut lasts: Vec<i64> = elig.iter().map(|&i| runs[i].last()).collect();
    lasts.sort_unstable();
    lasts.dedup();
    let mut tree: Vec<(u64, usize)> = vec![(0, usize::MAX); lasts.len() + 1];
    let mut best_at: Vec<(u64, usize)> = Vec::with_capacity(elig.len());
    for (j, &i) in elig.iter().enumerate() {
        let mut k = lasts.partition_point(|&x| x < runs[i].first);
        let mut before = (0u64, usize::MAX);
        while k > 0 {
            if tree[k].0 > before.0 {
                before = tree[k];
            }
            k &= k - 1;
        }
        let w = before.0 + runs[i].len;
        best_at.push((w, before.1));
        let mut k = lasts.partition_point(|&x| x < runs[i].last()) + 1;
        while k < tree.len() {
            if w > tree[k].0 {
                tree[k] = (w, j);
            }
            k += k & k.wrapping_neg();
        }
    }
    let mut end = (0..best_at.len()).max_by_key(|&j| (best_at[j].0, usize::MAX - j));
    let mut chain = Vec::new();
    while let Some(j) = end {
        chain.push(elig[j]);
        end = (best_at[j].1 != usize::MAX).then_some(best_at[j].1);
    }
    chain.reverse();
    chain
}

/// Decides what a walk of the ids `lo..hi` delivers and what it lost. `hi` is the next
/// stretch's first id (`None` at the end of the table, where the size of the last hole is
/// not known from the walk). `ts_of(id)` is the record time SQLite finds for `id` by its
/// key, to tell a page seen twice from a row whose id is damaged.
pub(crate) fn plan(
    walk: &Walk,
    lo: i64,
    hi: Option<i64>,
    ts_of: &mut dyn FnMut(i64) -> Option<i64>,
) -> Plan {
    let runs = &walk.runs;
    let bb = backbone(runs, lo, hi.unwrap_or(i64::MAX));
    let mut sorted: Vec<(i64, i64)> = bb
        .iter()
        .map(|&i| (runs[i].first, runs[i].last()))
        .collect();
    sorted.sort_unstable();
    let collides = |r: &Run| {
        let k = sorted.partition_point(|&(_, l)| l < r.first);
        k < sorted.len() && sorted[k].0 <= r.last()
    };
    let slots = Slots {
        runs,
        bb: &bb,
        lo,
        hi,
        breaks: breaks(walk),
    };
    let mut out = Plan {
        max_id: bb.last().map(|&i| (runs[i].last(), runs[i].ts_last)),
        min_id: bb.first().map(|&i| runs[i].first),
        ..Plan::default()
    };
    // Slot k lies before backbone run k (slot bb.len() after the last one).
    let mut pos = 0u64;
    let mut next_bb = 0usize;
    let mut slot_start_pos = 0u64;
    let mut filled = 0u64;
    for (i, r) in runs.iter().enumerate() {
        if next_bb < bb.len() && bb[next_bb] == i {
            slots.close(&mut out, next_bb, filled, slot_start_pos, pos);
            next_bb += 1;
            filled = 0;
            pos += r.len;
            slot_start_pos = pos;
            continue;
        }
        // An out-of-place run in slot `next_bb`.
        let double = collides(r) && ts_of(r.first) == Some(r.ts_first);
        let space = slots
            .room(next_bb)
            .map_or(u64::MAX, |x| x.saturating_sub(filled));
        let take = if double { 0 } else { r.len.min(space) };
        if take > 0 {
            out.moved.0 += take;
            out.moved.1.get_or_insert(r.first);
        }
        filled += take;
        out.doubles += r.len - take;
        out.skip_walked(pos + take, pos + r.len);
        pos += r.len;
    }
    slots.close(&mut out, next_bb, filled, slot_start_pos, pos);
    out
}

/// Walk positions where each segment's error struck.
fn breaks(walk: &Walk) -> Vec<(u64, &str)> {
    let mut breaks = Vec::new();
    let mut at = 0u64;
    for s in &walk.segments {
        at += s.rows;
        if let Some(e) = &s.error {
            breaks.push((at, e.as_str()));
        }
    }
    breaks
}

/// The id ranges between the backbone runs (slot `k` before backbone run `k`) that the
/// out-of-place runs fill.
struct Slots<'w> {
    runs: &'w [Run],
    bb: &'w [usize],
    lo: i64,
    hi: Option<i64>,
    breaks: Vec<(u64, &'w str)>,
}

impl Slots<'_> {
    /// The ids slot `k` has room for (`None`: unbounded, past the last part).
    fn room(&self, k: usize) -> Option<u64> {
        let (runs, bb) = (self.runs, self.bb);
        let before = if k == 0 {
            self.lo.checked_sub(1)
        } else {
            Some(runs[bb[k - 1]].last())
        };
        let after = if k < bb.len() {
            Some(runs[bb[k]].first)
        } else {
            self.hi
        };
        match (before, after) {
            (Some(b), Some(a)) => Some(a.saturating_sub(b).saturating_sub(1).max(0) as u64),
            _ => None,
        }
    }

    /// Slot `k`, `filled` of its room taken by rows walked at `from..to`: the rest is a hole
    /// (with the error that struck there, if one did).
    fn close(&self, out: &mut Plan, k: usize, filled: u64, from: u64, to: u64) {
        let (runs, bb) = (self.runs, self.bb);
        let Some(r) = self.room(k) else { return };
        if r <= filled {
            return;
        }
        let first = if k == 0 {
            self.lo
        } else {
            runs[bb[k - 1]].last() + 1
        };
        let last = first + r as i64 - 1;
        let error = self
            .breaks
            .iter()
            .find(|(p, _)| *p >= from && *p <= to)
            .map(|(_, e)| e.to_string());
        out.holes.push(Hole {
            ids: (first, last),
            lost: r - filled,
            around: (
                (k > 0).then(|| runs[bb[k - 1]].ts_last),
                (k < bb.len()).then(|| runs[bb[k]].ts_first),
            ),
            error,
        });
    }
}

impl Plan {
    /// Skips the walked rows `a..b` (joined to the skip before when they follow it).
    fn skip_walked(&mut self, a: u64, b: u64) {
        if a < b {
            match self.skip.last_mut() {
                Some(l) if l.1 == a => l.1 = b,
                _ => self.skip.push((a, b)),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A walk of the given ids (record time = 10 × id, as an undamaged table's).
    fn walk_of(ids: &[i64]) -> Walk {
        let mut w = Walk::default();
        for &id in ids {
            w.push(id, id * 10);
        }
        w.segments.push(Segment {
            seek: ids[0],
            rows: ids.len() as u64,
            error: None,
        });
        w
    }

    fn ts(id: i64) -> Option<i64> {
        Some(id * 10)
    }

    #[test]
    fn an_undamaged_table_is_one_run() {
        let ids: Vec<i64> = (1..=3000).collect();
        let w = walk_of(&ids);
        assert_eq!(w.runs.len(), 1);
        let p = plan(&w, 1, None, &mut ts);
        assert_eq!(
            p,
            Plan {
                max_id: Some((3000, 30_000)),
                min_id: Some(1),
                ..Plan::default()
            }
        );
    }

    /// A row whose id is damaged sits in the hole of its real id: delivered, nothing lost.
    #[test]
    fn a_damaged_row_id_fills_its_hole() {
        let mut ids: Vec<i64> = (1..=3000).collect();
        ids[1499] = 99_999;
        let mut w = walk_of(&ids);
        w.runs[1].ts_first = 15_000;
        let p = plan(&w, 1, None, &mut ts);
        assert!(p.holes.is_empty(), "{p:?}");
        assert_eq!(p.moved, (1, Some(99_999)));
        assert!(p.skip.is_empty());
        // Its damaged id may even repeat a later one: the record time tells them apart.
        ids[1499] = 2500;
        let mut w = walk_of(&ids);
        w.runs[1].ts_first = 15_000;
        let p = plan(&w, 1, None, &mut ts);
        assert!(p.holes.is_empty(), "{p:?}");
        assert_eq!(p.moved.0, 1);
    }

    /// Hidden rows (a lowered cell count) leave a hole the size of what is lost, with the
    /// record times around it.
    #[test]
    fn hidden_rows_are_a_hole() {
        let ids: Vec<i64> = (1..=3000).filter(|i| !(1201..=1278).contains(i)).collect();
        let p = plan(&walk_of(&ids), 1, None, &mut ts);
        assert_eq!(
            p.holes,
            vec![Hole {
                ids: (1201, 1278),
                lost: 78,
                around: (Some(12_000), Some(12_790)),
                error: None
            }]
        );
    }

    /// A page reached twice (a damaged child pointer) is read once; the page it replaced is
    /// a hole.
    #[test]
    fn a_page_seen_twice_is_read_once() {
        let mut ids: Vec<i64> = (1..=11).collect();
        ids.extend(23..=33);
        ids.extend(23..=33);
        ids.extend(34..=60);
        let p = plan(&walk_of(&ids), 1, None, &mut ts);
        assert_eq!(p.doubles, 11);
        assert_eq!(p.skip.len(), 1);
        assert_eq!(p.skip[0].1 - p.skip[0].0, 11);
        assert_eq!(p.holes.len(), 1);
        assert_eq!((p.holes[0].ids, p.holes[0].lost), ((12, 22), 11));
    }

    /// The stretch before the next part's first id is this part's: rows missing before it
    /// are lost; an error names the hole it opened.
    #[test]
    fn holes_up_to_the_next_part_and_errors() {
        let mut w = walk_of(&(100..=150).collect::<Vec<_>>());
        w.segments[0].error = Some("database disk image is malformed".into());
        let p = plan(&w, 100, Some(200), &mut ts);
        assert_eq!(p.holes.len(), 1);
        assert_eq!(p.holes[0].ids, (151, 199));
        assert_eq!(p.holes[0].lost, 49);
        assert!(p.holes[0].error.as_deref().unwrap().contains("malformed"));
    }

    /// The heaviest chain wins over a longer list of short runs.
    #[test]
    fn backbone_is_the_heaviest_chain() {
        let mut ids: Vec<i64> = vec![5000, 5001, 5002];
        ids.extend(1..=100);
        let w = walk_of(&ids);
        let bb = backbone(&w.runs, 1, i64::MAX);
        assert_eq!(bb, vec![1]);
        let ids: Vec<i64> = vec![1, 2, 3, 50, 4, 5, 6, 7, 8, 9, 60, 10, 11];
        let w = walk_of(&ids);
        let bb: Vec<(i64, u64)> = backbone(&w.runs, 1, i64::MAX)
            .iter()
            .map(|&i| (w.runs[i].first, w.runs[i].len))
            .collect();
        assert_eq!(bb, vec![(1, 3), (4, 6), (10, 2)]);
    }
}
