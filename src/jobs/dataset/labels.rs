//! `labels.jsonl`, read one way by everything that reads it (a run resuming, a merge,
//! `evaluate`, Python's `geltip.Dataset`): each line a JSON object naming its sample by an
//! integer `index`, no sample twice, blank lines skipped. The one line allowed to be bad is
//! a last line without its newline, which a run killed while appending leaves: it is left
//! out (its sample is not finished; a resumed run redoes it). Any other bad line is an error
//! naming the file and the line.

use crate::error::{GeltipError, Result};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::Path;

/// One sample's line.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelLine {
    /// The line's number in the file, from 1.
    pub line: usize,
    pub index: u64,
    /// The line as written.
    pub text: String,
    /// The line parsed: a JSON object.
    pub value: Value,
}

/// The lines of the labels file at `path`, in file order. A missing file is an I/O error.
pub fn read_labels(path: &Path) -> Result<Vec<LabelLine>> {
    let bytes = std::fs::read(path).map_err(|e| GeltipError::io(path, e))?;
    let text = String::from_utf8_lossy(&bytes);
    parse_labels(&text, &path.display().to_string())
}

/// The lines of a labels file's `text` (`what` names the file in errors).
pub fn parse_labels(text: &str, what: &str) -> Result<Vec<LabelLine>> {
    let torn_tail = !text.is_empty() && !text.ends_with('\n');
    let count = text.lines().count();
    let mut out: Vec<LabelLine> = Vec::new();
    let mut first: BTreeMap<u64, usize> = BTreeMap::new();
    for (n, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let at = || format!("{what}: line {}", n + 1);
        let last_unfinished = torn_tail && n + 1 == count;
        let value: Value = match serde_json::from_str(line) {
            Ok(v) => v,
            Err(_) if last_unfinished => break,
            Err(e) => return Err(GeltipError::input(at(), format!("not valid JSON: {e}"))),
        };
        if !value.is_object() {
            if last_unfinished {
                break;
            }
            return Err(GeltipError::input(at(), "expected a JSON object"));
        }
        let index = value["index"]
            .as_u64()
            .ok_or_else(|| GeltipError::input(at(), "index: required, an integer >= 0"))?;
        if let Some(first) = first.insert(index, n + 1) {
            return Err(GeltipError::input(
                at(),
                format!("index: sample {index} again (first on line {first})"),
            ));
        }
        out.push(LabelLine {
            line: n + 1,
            index,
            text: line.to_string(),
            value,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_an_unfinished_last_line_may_be_bad() {
        let a = r#"{"index": 1, "image": "a"}"#;
        let b = r#"{"index": 0, "image": "b"}"#;
        let lines = parse_labels(&format!("{a}\n\n{b}\n{{\"index\": 2, \"ima"), "L").unwrap();
        assert_eq!(
            lines.iter().map(|l| (l.line, l.index)).collect::<Vec<_>>(),
            [(1, 1), (3, 0)]
        );
        assert_eq!(lines[1].text, b);
        let finished = parse_labels(&format!("{a}\n{b}"), "L").unwrap();
        assert_eq!(
            finished.len(),
            2,
            "a whole last line without its newline is kept"
        );
        for (text, says) in [
            (format!("{{\"ind\n{a}\n"), "L: line 1: not valid JSON"),
            (
                format!("{a}\n{{\"index\": 2, \"ima\n"),
                "L: line 2: not valid JSON",
            ),
            (format!("{a}\n[1]\n"), "L: line 2: expected a JSON object"),
            (
                format!("{a}\n{{\"index\": -1}}\n"),
                "L: line 2: index: required",
            ),
            (
                format!("{a}\n{a}\n"),
                "L: line 2: index: sample 1 again (first on line 1)",
            ),
        ] {
            let e = parse_labels(&text, "L").unwrap_err().to_string();
            assert!(e.starts_with(says), "{text:?}: {e}");
        }
    }
}
