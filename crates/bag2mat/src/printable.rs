//! Text from an input (a topic name, a type, a file name) as the tools print it: control
//! characters escaped. Its own module because the errors print such text too, and they sit
//! below the command-line helpers.

/// Text from a file (a topic name, a type) made safe to print: control characters are
/// escaped, so a damaged or hostile name cannot move the cursor or clear the terminal.
pub fn escape(s: &str) -> String {
    if !s.chars().any(|c| c.is_control()) {
        return s.to_string();
    }
    s.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_characters_are_escaped() {
        assert_eq!(escape("/imu"), "/imu");
        assert_eq!(escape("/i\x1b[2Jmu\n"), "/i\\u{1b}[2Jmu\\n");
    }
}
