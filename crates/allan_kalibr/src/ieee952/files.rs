//! (in progress)

/// The sample count a curves file states in its `# samples=N` comment line.
pub fn stated_samples(text: &str) -> Option<usize> {
    text.lines()
        .take_while(|l| l.starts_with('#'))
        .find_map(|l| {
            l.split(|c: char| c == ',' || c.is_whitespace())
                .find_map(|w| w.strip_prefix("samples="))
                .and_then(|v| v.parse().ok())
        })
}
