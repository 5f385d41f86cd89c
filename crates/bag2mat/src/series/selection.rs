//! Which channels of a source a read takes: the topic rules (exact name, else the other
//! slash form with a note; every Imu topic with `--all-imu-topics`) and the missing-topic
//! error that lists what is there.

use super::*;

/// A selected topic: its name in the bag, its channels and how they decode.
pub(super) struct Selected {
    pub(super) topic: String,
    pub(super) msg_type: String,
    pub(super) channels: Vec<(u32, Codec)>,
    pub(super) note: Option<String>,
    /// Named by the user (not only found by `all_imu`).
    pub(super) named: bool,
}

pub(super) fn other_slash_form(topic: &str) -> String {
    match topic.strip_prefix('/') {
        Some(rest) => rest.to_string(),
        None => format!("/{topic}"),
    }
}

/// The distinct topics of `chans` that carry `sensor_msgs/Imu`, sorted.
pub(super) fn imu_topics(chans: &[Channel]) -> Vec<&str> {
    let mut topics: Vec<&str> = chans
        .iter()
        .filter(|c| is_imu(c))
        .map(|c| c.topic.as_str())
        .collect();
    topics.sort();
    topics.dedup();
    topics
}

pub(super) fn select(src: &dyn Source, sel: &TopicSelector) -> Result<Vec<Selected>, Error> {
    let chans = src.channels();
    if chans.is_empty() {
        // Say why there is nothing (truncated, damaged) rather than "no topics".
        let mut why: Vec<String> = src.notes().iter().map(|n| n.text.clone()).collect();
        why.extend(src.losses().iter().map(|l| l.to_string()));
        return Err(Error::NoTopics { why });
    }
    let on = |t: &str| channels_on(chans, t);
    let mut out: Vec<Selected> = Vec::new();
    for t in &sel.topics {
        let cs = on(t);
        if !cs.is_empty() {
            push_selected(&mut out, t.clone(), cs, None, true)?;
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
        let note = format!(
            "topic '{}' is not in the bag; using '{}'",
            crate::printable::escape(t),
            crate::printable::escape(&other)
        );
        push_selected(&mut out, other, cs, Some(note), true)?;
    }
    if sel.topics.is_empty() && !sel.all_imu {
        select_default(src, sel, &mut out)?;
        return Ok(out);
    }
    if sel.all_imu {
        let before = out.len();
        for t in imu_topics(chans) {
            // A topic that mixes Imu with another type gives its Imu connection (with a note).
            push_selected(&mut out, t.to_string(), on(t), None, false)?;
        }
        if out.is_empty() && before == 0 {
            return Err(Error::NoImuTopic {
                available: topic_summaries(src),
            });
        }
    }
    Ok(out)
}

/// The channels recorded on `topic`.
pub(super) fn channels_on<'a>(chans: &'a [Channel], topic: &str) -> Vec<&'a Channel> {
    chans.iter().filter(|c| c.topic == topic).collect()
}

/// No topic named: the preferred one (in either slash form), else the only Imu topic.
pub(super) fn select_default(
    src: &dyn Source,
    sel: &TopicSelector,
    out: &mut Vec<Selected>,
) -> Result<(), Error> {
    let chans = src.channels();
    let on = |t: &str| channels_on(chans, t);
    if let Some(p) = &sel.preferred {
        let other = other_slash_form(p);
        if let Some(t) = [p, &other].into_iter().find(|t| !on(t).is_empty()) {
            return push_selected(out, t.clone(), on(t), None, true);
        }
    }
    match imu_topics(chans)[..] {
        [] => Err(Error::NoImuTopic {
            available: topic_summaries(src),
        }),
        [t] => {
            let missing = match &sel.preferred {
                Some(p) => format!(" and no '{}'", crate::printable::escape(p)),
                None => String::new(),
            };
            let note = format!(
                "no topic named{missing}: reading '{}', the only sensor_msgs/Imu topic",
                crate::printable::escape(t)
            );
            push_selected(out, t.to_string(), on(t), Some(note), true)
        }
        _ => Err(Error::SeveralImuTopics {
            available: topic_summaries(src),
        }),
    }
}

/// Adds `topic` (its channels `cs`) to the selection, once: its Imu channels, with a note
/// when it also carries another type; an error when it carries no Imu at all.
pub(super) fn push_selected(
    out: &mut Vec<Selected>,
    topic: String,
    cs: Vec<&Channel>,
    note: Option<String>,
    named: bool,
) -> Result<(), Error> {
    if out.iter().any(|s| s.topic == topic) {
        return Ok(());
    }
    let mut channels = Vec::new();
    let mut others: Vec<&Channel> = Vec::new();
    for c in &cs {
        match imu_codec(c) {
            Some(k) => channels.push((c.id, k)),
            None => others.push(c),
        }
    }
    let Some(first_other) = others.first() else {
        out.push(Selected {
            topic,
            msg_type: cs[0].msg_type.clone(),
            channels,
            note,
            named,
        });
        return Ok(());
    };
    if channels.is_empty() {
        return Err(Error::WrongType {
            topic: topic.clone(),
            msg_type: first_other.msg_type.clone(),
            md5sum: first_other
                .md5sum
                .clone()
                .unwrap_or_else(|| format!("encoding {}", first_other.encoding.name())),
        });
    }
    // Imu plus another type on one topic: the Imu connection is converted, as
    // bagconvert's rosbag::View + instantiate<sensor_msgs::Imu>() skips the others.
    let other_types: Vec<String> = others
        .iter()
        .map(|c| {
            format!(
                "{} ({} messages)",
                crate::printable::escape(&c.msg_type),
                c.count.map_or("?".to_string(), |n| n.to_string())
            )
        })
        .collect();
    let mixed = format!(
        "topic '{}' also carries {}; only its sensor_msgs/Imu connection is converted, as bagconvert does",
        crate::printable::escape(&topic),
        other_types.join(", ")
    );
    let note = Some(match note {
        Some(n) => format!("{n}; {mixed}"),
        None => mixed,
    });
    let msg_type = cs
        .iter()
        .find(|c| is_imu(c))
        .map(|c| c.msg_type.clone())
        .unwrap_or_default();
    out.push(Selected {
        topic,
        msg_type,
        channels,
        note,
        named,
    });
    Ok(())
}
