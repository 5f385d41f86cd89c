//! What a run tells the user besides its results: typed notes, so that no code decides from
//! a message's text whether it is a warning.
//!
//! A [`Note`] is said on stderr by the binary's one `finish`: a warning always (as
//! `warning: <text>`), information only without `--quiet`.

use std::fmt;

/// How much a note matters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    /// Something the user may want to know (how the rate was found, which topic was read).
    Info,
    /// Something that makes a result less trustworthy or different from what was asked.
    Warning,
}

/// One thing to tell the user.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Note {
    /// Warning or information.
    pub level: Level,
    /// What to say, without a `warning:` prefix.
    pub text: String,
    /// The prefix the upstream tool itself prints before this text (imu_utils'
    /// `WARNING: `), kept in the note's [`Display`](fmt::Display) for parity with upstream's
    /// stderr; the binaries say every warning the one way ([`Note::line`]).
    pub upstream_prefix: Option<&'static str>,
}

impl Note {
    /// A note for information.
    pub fn info(text: impl Into<String>) -> Note {
        Note {
            level: Level::Info,
            text: text.into(),
            upstream_prefix: None,
        }
    }

    /// A warning.
    pub fn warning(text: impl Into<String>) -> Note {
        Note {
            level: Level::Warning,
            text: text.into(),
            upstream_prefix: None,
        }
    }

    /// A warning the upstream tool prints itself, after `prefix`.
    pub fn upstream_warning(prefix: &'static str, text: impl Into<String>) -> Note {
        Note {
            upstream_prefix: Some(prefix),
            ..Note::warning(text)
        }
    }

    /// Information the upstream tool prints itself as a warning, after `prefix` (kept for
    /// parity with upstream's stderr), which this tool says as information: a message that
    /// every ordinary run would print is not a warning.
    pub fn upstream_info(prefix: &'static str, text: impl Into<String>) -> Note {
        Note {
            upstream_prefix: Some(prefix),
            ..Note::info(text)
        }
    }

    /// The line on stderr: `warning: <text>` or the text.
    pub fn line(&self) -> String {
        match self.level {
            Level::Warning => format!("warning: {}", self.text),
            Level::Info => self.text.clone(),
        }
    }

    /// True for a warning.
    pub fn is_warning(&self) -> bool {
        self.level == Level::Warning
    }
}

/// The note as upstream would print it: [`Note::line`], or the upstream tool's own prefix.
impl fmt::Display for Note {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.upstream_prefix {
            Some(p) => write!(f, "{p}{}", self.text),
            None => f.write_str(&self.line()),
        }
    }
}

/// Every note's text, one per line (no level prefix): what a message or a test that looks for
/// one of them reads.
pub fn texts(notes: &[Note]) -> String {
    notes
        .iter()
        .map(|n| n.text.as_str())
        .collect::<Vec<_>>()
        .join("\n")
}
