//! What the container promised against what was delivered: the per-topic tally of lost,
//! undecodable and skipped messages and the notes that say so.

use super::*;
use crate::shared::note::Note;

/// Messages lost on one topic, as the losses found count them.
#[derive(Default)]
pub(super) struct LossTally {
    /// Counted on this topic.
    pub(super) exact: u64,
    /// Of unknown topic (could be this one's), counted or bounded.
    pub(super) unknown_topic: u64,
    /// This topic's, bounded (the damaged bytes can have held at most this many).
    pub(super) bounded: u64,
    /// Some loss has no count at all.
    pub(super) uncounted: bool,
    /// A loss on no particular channel is this topic's: the source has no other.
    pub(super) only_topic: bool,
}

impl LossTally {
    pub(super) fn count(&mut self, l: &Loss, mine: bool) {
        match (l.messages, l.at_most) {
            (Some(n), _) if mine || self.only_topic => self.exact = self.exact.saturating_add(n),
            (Some(n), _) => self.unknown_topic = self.unknown_topic.saturating_add(n),
            (None, Some(n)) if mine && l.channel.is_some() => {
                self.bounded = self.bounded.saturating_add(n)
            }
            (None, Some(n)) => self.unknown_topic = self.unknown_topic.saturating_add(n),
            (None, None) => self.uncounted = true,
        }
    }
}

/// The losses of topic `k` (selected as `s`) the parts found, or that their counts show,
/// into its report and tally.
pub(super) fn part_losses(
    parts: &[source::Part],
    outs: &[PartOut],
    k: usize,
    s: &Selected,
    r: &mut TopicReport,
    tally: &mut LossTally,
) {
    let mine_ch = |c: &u32| s.channels.iter().any(|(id, _)| id == c);
    for (i, o) in outs.iter().enumerate() {
        let p = &parts[i];
        let mine: Option<u64> = p.counts.as_ref().map(|v| {
            v.iter()
                .filter(|(c, _)| mine_ch(c))
                .map(|(_, n)| *n)
                .fold(0u64, |a, b| a.saturating_add(b))
        });
        let got = o.rows[k] + o.bad[k];
        // What the part itself found lost on this topic (or on no particular channel).
        let mut known = 0u64;
        for l in &o.read.lost {
            match l.channel {
                Some(c) if mine_ch(&c) => {
                    known += l.messages.unwrap_or(0);
                    tally.count(l, true);
                    r.losses.push(l.clone());
                }
                None if mine != Some(0) => {
                    tally.count(l, false);
                    r.losses.push(l.clone());
                }
                _ => {}
            }
        }
        let reason = match (&o.read.error, o.read.skipped) {
            (Some(e), _) => Some(e.to_string()),
            (None, n) if n > 0 => o.read.skip_reason.as_ref().map(|s| s.to_string()),
            _ => None,
        };
        let rest = mine.map(|m| m.saturating_sub(got.saturating_add(known)));
        let l = if let Some(reason) = reason {
            if mine == Some(0) {
                continue;
            }
            Loss {
                what: format!("{}: {reason}", p.label),
                messages: rest,
                span: p.span,
                ..Loss::default()
            }
        } else if rest.is_some_and(|n| n > 0) {
            Loss {
                what: format!(
                    "{} holds {got} messages of '{}', its index says {}",
                    p.label,
                    s.topic,
                    mine.unwrap_or(0)
                ),
                messages: rest,
                span: p.span,
                ..Loss::default()
            }
        } else {
            continue;
        };
        // Counted from this topic's own promise for the part.
        tally.count(&l, true);
        r.losses.push(l);
    }
}

/// The notes that say how many messages of `topic` were lost, or may have been, and how
/// many did not decode. `no_container_loss`: the container itself reported none.
pub(super) fn loss_notes(
    notes: &mut Vec<Note>,
    r: &TopicReport,
    topic: &str,
    tally: &LossTally,
    no_container_loss: bool,
) {
    let exact = tally.exact;
    // Whatever the parts said, the container's own promise is checked as a whole.
    let missing = match r.promised {
        Some(p) => p.saturating_sub(r.delivered + r.undecodable).max(exact),
        None => exact,
    };
    // Without a promise, losses of unknown topic may be this topic's: said as a bound.
    // With a promise, what it finds missing beyond the counted losses may be those of
    // unknown topic; the rest of them are said as a bound.
    let (more, uncounted) = match r.promised {
        Some(_) => (
            tally
                .unknown_topic
                .saturating_add(tally.bounded)
                .saturating_sub(missing.saturating_sub(exact)),
            false,
        ),
        None => (
            tally.unknown_topic.saturating_add(tally.bounded),
            tally.uncounted,
        ),
    };
    let why = if tally.unknown_topic > 0 {
        " (messages of unknown topic were lost)"
    } else {
        ""
    };
    let see = if r.losses.is_empty() && no_container_loss {
        " (the container promises them; none of its parts could say where)"
    } else {
        " (see above)"
    };
    let tail = if uncounted {
        ", and more that the damaged data does not count (see above)"
    } else {
        see
    };
    if missing > 0 {
        notes.push(Note::warning(format!(
            "{missing} of {} messages on '{}' were lost{}{tail}",
            // a loss a reader counted beyond its promise (a batch short of its header)
            // belongs to the total too
            r.promised
                .map_or(r.delivered + missing, |p| p.max(r.delivered + missing)),
            topic,
            if more > 0 {
                format!(", and up to {more} more{why}")
            } else {
                String::new()
            }
        )));
    } else if more > 0 {
        notes.push(Note::warning(format!(
            "up to {more} messages on '{}' were lost{why}{tail}",
            topic
        )));
    } else if uncounted {
        notes.push(Note::warning(format!(
            "messages on '{}' may have been lost: the damaged data does not count them (see above)",
            topic
        )));
    }
    if r.undecodable > 0 {
        notes.push(Note::warning(format!(
            "{} messages on '{}' do not decode as sensor_msgs/Imu and were skipped (first: {})",
            r.undecodable,
            topic,
            r.first_error.as_deref().unwrap_or("?")
        )));
    }
}

/// The topics not read, with their message counts, by topic and type.
pub(super) fn skipped_topics(src: &dyn Source, lookup: &Lookup) -> Vec<TopicSummary> {
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
    skipped
        .into_iter()
        .map(|((topic, msg_type), count)| TopicSummary {
            topic,
            msg_type,
            count,
        })
        .collect()
}
