//! Reads an imu_utils roslaunch file as it is (`<node …><param name=… type=… value=…/>`),
//! so users can keep their launch files. Only the five parameters imu_utils reads are used
//! (docs/upstream/imu_utils.md §1). Substitutions such as `$(find imu_utils)` need ROS to resolve; they are
//! kept as [`LaunchValue::Unresolved`] and become an error naming the flag to give instead,
//! unless that flag was given anyway.

use std::path::Path;

use crate::error::{Error, LaunchSyntax};

/// The imu_utils parameters and the flag that replaces each.
pub const PARAMS: [(&str, &str); 5] = [
    ("imu_topic", "--topic"),
    ("imu_name", "--name"),
    ("data_save_path", "--data-save-path"),
    ("max_time_min", "--max-time-min"),
    ("max_cluster", "--max-cluster"),
];

/// The flag for a parameter name.
pub(crate) fn flag_for(param: &str) -> &'static str {
    PARAMS
        .iter()
        .find(|(p, _)| *p == param)
        .map(|(_, f)| *f)
        .unwrap_or("the matching flag")
}

/// A parameter's value as written in the file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LaunchValue {
    /// A plain value.
    Value(String),
    /// A value with a `$(…)` substitution that needs ROS.
    Unresolved(String),
}

/// The imu_utils parameters found in a launch file.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct LaunchParams {
    /// (parameter name, value), in file order; later entries win.
    pub params: Vec<(String, LaunchValue)>,
}

impl LaunchParams {
    /// The last value given for `name`.
    pub(crate) fn get(&self, name: &str) -> Option<&LaunchValue> {
        self.params
            .iter()
            .rev()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v)
    }
}

/// Reads and parses a launch file.
pub(crate) fn read(path: &Path) -> Result<LaunchParams, Error> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::Io {
        path: path.to_path_buf(),
        cause: e,
    })?;
    parse(&text).map_err(|what| Error::Launch {
        path: path.to_path_buf(),
        what,
    })
}

fn strip_comments(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut rest = s;
    while let Some(i) = rest.find("<!--") {
        out.push_str(&rest[..i]);
        match rest[i..].find("-->") {
            Some(j) => rest = &rest[i + j + 3..],
            None => return out,
        }
    }
    out.push_str(rest);
    out
}

fn unescape(s: &str) -> String {
    s.replace("&quot;", "\"")
        .replace("&apos;", "'")
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&")
}

/// Parses `key = "value"` attributes of one tag body.
fn attributes(body: &str) -> Result<Vec<(String, String)>, LaunchSyntax> {
    let mut out = Vec::new();
    let b = body.as_bytes();
    let mut i = 0;
    while i < b.len() {
        while i < b.len() && (b[i].is_ascii_whitespace() || b[i] == b'/') {
            i += 1;
        }
        if i >= b.len() {
            break;
        }
        let start = i;
        while i < b.len() && !b[i].is_ascii_whitespace() && b[i] != b'=' {
            i += 1;
        }
        let key = &body[start..i];
        while i < b.len() && b[i].is_ascii_whitespace() {
            i += 1;
        }
        if i >= b.len() || b[i] != b'=' {
            return Err(LaunchSyntax(format!("attribute '{key}' has no value")));
        }
        i += 1;
        while i < b.len() && b[i].is_ascii_whitespace() {
            i += 1;
        }
        if i >= b.len() || (b[i] != b'"' && b[i] != b'\'') {
            return Err(LaunchSyntax(format!(
                "attribute '{key}' value is not quoted"
            )));
        }
        let q = b[i];
        i += 1;
        let vstart = i;
        while i < b.len() && b[i] != q {
            i += 1;
        }
        if i >= b.len() {
            return Err(LaunchSyntax(format!(
                "attribute '{key}' value is not closed"
            )));
        }
        out.push((key.to_string(), unescape(&body[vstart..i])));
        i += 1;
    }
    Ok(out)
}

/// Parses launch-file text.
pub(crate) fn parse(text: &str) -> Result<LaunchParams, LaunchSyntax> {
    let text = strip_comments(text);
    if !text.contains("<launch") {
        return Err(LaunchSyntax(
            "not a roslaunch file (no <launch> element)".into(),
        ));
    }
    let mut params = Vec::new();
    let mut rest = text.as_str();
    while let Some(i) = rest.find("<param") {
        let after = &rest[i + 6..];
        if !after.starts_with(|c: char| c.is_ascii_whitespace()) {
            rest = after;
            continue;
        }
        // The tag ends at the first '>' outside quotes.
        let mut quote = None;
        let mut end = None;
        for (k, c) in after.char_indices() {
            match (quote, c) {
                (None, '"' | '\'') => quote = Some(c),
                (Some(q), c) if c == q => quote = None,
                (None, '>') => {
                    end = Some(k);
                    break;
                }
                _ => {}
            }
        }
        let end = end.ok_or_else(|| LaunchSyntax("unterminated <param> tag".into()))?;
        let attrs = attributes(&after[..end])?;
        rest = &after[end + 1..];
        let get = |k: &str| attrs.iter().find(|(a, _)| a == k).map(|(_, v)| v.clone());
        let Some(name) = get("name") else { continue };
        // Parameters may be given with a private prefix (`~imu_topic`) or a namespace.
        let short = name.rsplit(['/', '~']).next().unwrap_or(&name).to_string();
        if !PARAMS.iter().any(|(p, _)| *p == short) {
            continue;
        }
        let Some(value) = get("value") else {
            return Err(LaunchSyntax(format!(
                "<param name=\"{name}\"> has no value attribute (command/textfile need ROS); give {} instead",
                flag_for(&short)
            )));
        };
        let value = if value.contains("$(") {
            LaunchValue::Unresolved(value)
        } else {
            LaunchValue::Value(value.trim().to_string())
        };
        params.push((short, value));
    }
    if params.is_empty() {
        return Err(LaunchSyntax("no imu_utils <param> (imu_topic, imu_name, data_save_path, max_time_min, max_cluster) found".into()));
    }
    Ok(LaunchParams { params })
}

#[cfg(test)]
mod tests {
    use super::*;

    const UPSTREAM_STYLE: &str = r#"<launch>
    <node pkg="imu_utils" type="imu_an" name="imu_an" output="screen">
        <!-- <param name="imu_topic" type="string" value= "/commented"/> -->
        <param name="imu_topic" type="string" value= "/imu"/>
        <param name="imu_name" type="string" value= "imu"/>
        <param name="data_save_path" type="string" value= "$(find imu_utils)/data/"/>
        <param name="max_time_min" type="int" value= "120"/>
        <param name="max_cluster" type="int" value= "100"/>
    </node>
</launch>
"#;

    #[test]
    fn reads_upstream_launch_layout() {
        let p = parse(UPSTREAM_STYLE).unwrap();
        assert_eq!(p.get("imu_topic"), Some(&LaunchValue::Value("/imu".into())));
        assert_eq!(
            p.get("max_cluster"),
            Some(&LaunchValue::Value("100".into()))
        );
        assert_eq!(
            p.get("data_save_path"),
            Some(&LaunchValue::Unresolved("$(find imu_utils)/data/".into()))
        );
        assert_eq!(p.params.len(), 5);
    }

    #[test]
    fn rejects_what_is_not_a_launch_file() {
        assert!(parse("hello").is_err());
        assert!(
            parse("<launch></launch>")
                .unwrap_err()
                .0
                .contains("no imu_utils")
        );
        assert!(parse("<launch><param name=\"imu_topic\" value=\"/a></launch>").is_err());
    }
}
