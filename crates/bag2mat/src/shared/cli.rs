//! How every binary of the workspace ends: one convention for all four tools.
//!
//! * A failure prints `<tool>: error: <what>: <cause>` once on stderr and exits with 1.
//! * A usage error (what the user typed cannot be run) prints `<tool>: error: <what>`, the
//!   usage lines, and exits with 2.
//! * Warnings are `warning: <what>` lines; `--quiet` keeps only errors and warnings.
//!
//! The argument parser stays in each binary; these helpers take its rendered text.

use std::process::ExitCode;

/// Exit status of a run that failed.
pub const EXIT_FAILURE: u8 = 1;
/// Exit status of a command line that cannot be run.
pub const EXIT_USAGE: u8 = 2;

/// Runs `write` on (buffered) standard output. A reader that closed the pipe early (`tool …
/// | head`) is not an error, as for every Unix filter: `Ok(false)` says to write no more.
pub fn to_stdout(
    write: impl FnOnce(&mut dyn std::io::Write) -> std::io::Result<()>,
) -> std::io::Result<bool> {
    use std::io::Write;
    let mut out = std::io::BufWriter::with_capacity(1 << 20, std::io::stdout().lock());
    match write(&mut out).and_then(|_| out.flush()) {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(false),
        Err(e) => Err(e),
    }
}

/// Writes `text` to standard output ([`to_stdout`]); other failures come back as the I/O
/// error of "standard output", described plainly (no "os error N").
pub fn print(text: &str) -> Result<bool, crate::Error> {
    to_stdout(|w| w.write_all(text.as_bytes())).map_err(|e| crate::Error::io("standard output", e))
}

/// A command line that cannot be run as given (exit status [`EXIT_USAGE`]): what is wrong
/// and what to give instead.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct UsageError(pub String);

/// Prints a failure the one way, and returns exit status 1.
pub fn fail(tool: &str, what: &dyn std::fmt::Display) -> ExitCode {
    eprintln!("{tool}: error: {what}");
    ExitCode::from(EXIT_FAILURE)
}

/// Prints a usage error (`rendered` is the parser's message, which may start with
/// `error: ` and carry usage lines after it) and returns exit status 2.
pub fn usage(tool: &str, rendered: &str) -> ExitCode {
    let text = rendered.trim_end();
    let text = text.strip_prefix("error: ").unwrap_or(text);
    eprintln!("{tool}: error: {text}");
    ExitCode::from(EXIT_USAGE)
}

/// A value parser for numbers that must be finite and positive: "must be positive" (not
/// the parser's "unexpected argument '-1'", which the binaries avoid by accepting negative
/// numbers as values).
pub fn positive_f64(s: &str) -> Result<f64, UsageError> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| UsageError(format!("'{s}' is not a number")))?;
    if !v.is_finite() || v <= 0.0 {
        return Err(UsageError(format!("{s} must be positive (and finite)")));
    }
    Ok(v)
}

/// Flags that only apply with another one: a usage error naming those given without it
/// (clap's `requires` does not see an empty repeatable flag as absent here).
pub fn only_with(needed: &str, present: bool, flags: &[(&str, bool)]) -> Result<(), UsageError> {
    let given: Vec<&str> = flags.iter().filter(|f| f.1).map(|f| f.0).collect();
    if present || given.is_empty() {
        return Ok(());
    }
    Err(UsageError(format!(
        "{} only appl{} with {needed}, which was not given",
        given.join(", "),
        if given.len() == 1 { "ies" } else { "y" }
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positive_numbers() {
        assert_eq!(positive_f64("200"), Ok(200.0));
        assert!(
            positive_f64("-1")
                .unwrap_err()
                .0
                .contains("must be positive")
        );
        assert!(
            positive_f64("0")
                .unwrap_err()
                .0
                .contains("must be positive")
        );
        assert!(
            positive_f64("nan")
                .unwrap_err()
                .0
                .contains("must be positive")
        );
        assert!(positive_f64("abc").unwrap_err().0.contains("not a number"));
    }
}
