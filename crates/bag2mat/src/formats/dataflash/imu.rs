//! The `IMU` messages put together once the whole log is read: ArduPilot logs every IMU
//! instance once per loop with the same `TimeUS` (`AP_InertialSensor::Write_IMU`), so a
//! loop's messages are a cycle of distinct instances in a fixed order. A message whose
//! instance byte is damaged (DataFlash has no checksum) breaks its cycle — an instance twice,
//! or one the log does not have — and is given back to the instance its cycle lacks.

use std::collections::HashMap;

use crate::rows::Row;

/// An `IMU` message as read: file offset, `TimeUS`, instance (as stored) and row.
#[derive(Debug, Clone)]
pub(super) struct Msg {
    pub(super) at: usize,
    pub(super) t_us: u64,
    pub(super) inst: u32,
    pub(super) row: Row,
}

/// What the repair did: messages given back to their instance (count, first offset), and
/// messages of an instance the log does not have that could not be (count, first offset).
#[derive(Debug, Default)]
pub(super) struct Repair {
    pub(super) moved: (u64, usize),
    pub(super) dropped: (u64, usize),
}

/// An instance is one of the log's when it has this share of the messages of the most
/// logged instance (a damaged byte makes a lone message of another).
const INSTANCE_SHARE: f64 = 0.01;
/// ... and at least this many messages.
const MIN_INSTANCE_MSGS: usize = 3;

/// Repairs the instances of `msgs` (in file order) by their cycles; returns what it did.
pub(super) fn repair(msgs: &mut Vec<Msg>) -> Repair {
    let mut r = Repair::default();
    let mut count: HashMap<u32, usize> = HashMap::new();
    for m in msgs.iter() {
        *count.entry(m.inst).or_default() += 1;
    }
    let most = count.values().copied().max().unwrap_or(0);
    let known = |i: u32| {
        count
            .get(&i)
            .is_some_and(|&n| n >= MIN_INSTANCE_MSGS && n as f64 >= INSTANCE_SHARE * most as f64)
    };
    let mut instances: Vec<u32> = count.keys().copied().filter(|&i| known(i)).collect();
    instances.sort_unstable();
    if instances.is_empty() {
        return r;
    }
    // the usual order of a cycle: the first one that holds every instance once
    let mut order: Vec<u32> = instances.clone();
    let cycles = cycle_bounds(msgs);
    for &(a, b) in &cycles {
        let insts: Vec<u32> = msgs[a..b].iter().map(|m| m.inst).collect();
        let mut sorted = insts.clone();
        sorted.sort_unstable();
        if sorted == instances {
            order = insts;
            break;
        }
    }
    let mut drop = vec![false; msgs.len()];
    for &(a, b) in &cycles {
        let cyc = &msgs[a..b];
        let mut good: Vec<bool> = vec![true; cyc.len()];
        for (k, m) in cyc.iter().enumerate() {
            let twice = cyc.iter().filter(|x| x.inst == m.inst).count() > 1;
            // of two with one instance, the one away from its place in the usual order
            let misplaced = twice && order.get(k) != Some(&m.inst);
            if !known(m.inst) || misplaced {
                good[k] = false;
            }
        }
        if good.iter().all(|&g| g) {
            continue;
        }
        let mut absent: Vec<u32> = order
            .iter()
            .copied()
            .filter(|i| !cyc.iter().zip(&good).any(|(m, g)| *g && m.inst == *i))
            .collect();
        for k in 0..cyc.len() {
            if good[k] {
                continue;
            }
            let at = msgs[a + k].at;
            // its place in the usual order, else the only instance the cycle lacks
            let to = match order.get(k) {
                Some(i) if absent.contains(i) => Some(*i),
                _ if absent.len() == 1 => Some(absent[0]),
                _ => None,
            };
            match to {
                Some(i) => {
                    absent.retain(|x| *x != i);
                    msgs[a + k].inst = i;
                    if r.moved.0 == 0 {
                        r.moved.1 = at;
                    }
                    r.moved.0 += 1;
                }
                None if !known(msgs[a + k].inst) => {
                    drop[a + k] = true;
                    if r.dropped.0 == 0 {
                        r.dropped.1 = at;
                    }
                    r.dropped.0 += 1;
                }
                None => {}
            }
        }
    }
    let mut k = 0;
    msgs.retain(|_| {
        k += 1;
        !drop[k - 1]
    });
    r
}

/// The cycles of `msgs`: runs of messages with one `TimeUS`, as index ranges.
fn cycle_bounds(msgs: &[Msg]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut a = 0;
    for i in 1..=msgs.len() {
        if i == msgs.len() || msgs[i].t_us != msgs[a].t_us {
            out.push((a, i));
            a = i;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn msg(t: u64, inst: u32) -> Msg {
        Msg {
            at: t as usize,
            t_us: t,
            inst,
            row: Row {
                stamp: t,
                acc: [0.0; 3],
                gyro: [inst as f64; 3],
            },
        }
    }

    #[test]
    fn a_damaged_instance_goes_back_to_the_instance_its_cycle_lacks() {
        let mut v: Vec<Msg> = (0..50).flat_map(|t| [msg(t, 0), msg(t, 1)]).collect();
        v[20].inst = 1; // cycle 10: instance 0 stored as 1
        v[31].inst = 128; // cycle 15: instance 1 stored as 128
        v[41].inst = 0; // cycle 20: instance 1 stored as 0
        let r = repair(&mut v);
        assert_eq!(r.moved.0, 3);
        assert_eq!(r.dropped.0, 0);
        assert!(v.iter().all(|m| m.row.gyro[0] as u32 == m.inst));
        // a single instance: a lone damaged one is its
        let mut v: Vec<Msg> = (0..50).map(|t| msg(t, 0)).collect();
        v[7].inst = 4;
        assert_eq!(repair(&mut v).moved.0, 1);
        assert!(v.iter().all(|m| m.inst == 0));
    }
}
