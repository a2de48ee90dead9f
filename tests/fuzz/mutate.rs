//! Structure-aware mutations: a text is cut into tokens (numbers, strings, words,
//! punctuation) and lines, so numbers become NaN, infinities, huge, negative, zero or -0,
//! values change type, lines and tokens are deleted, duplicated and swapped, values are
//! nested deeply; a JSON document is also mutated as a tree (so it stays valid JSON and
//! reaches the checks behind the syntax); binary formats are mutated chunk by chunk (see
//! [`super::binary`]). Blind byte flips and truncations are mixed in.

use super::binary;
use super::dictionary;
use super::{Format, Rng};
use serde_json::Value;

/// Inputs grow no larger than this (a mutation that would is skipped).
const MAX_LEN: usize = 4 << 20;

/// One case from `seed`: one to three mutations of the format's kinds.
pub fn mutate(format: Format, rng: &mut Rng, seed: &[u8], seeds: &[Vec<u8>]) -> Vec<u8> {
    let mut data = seed.to_vec();
    for _ in 0..1 + rng.below(3) {
        let next = match format {
            Format::Json if rng.chance(0.6) => {
                json_tree(rng, &data).unwrap_or_else(|| text(rng, &data, seeds, Flavor::Json))
            }
            Format::Json => text(rng, &data, seeds, Flavor::Json),
            Format::JsonLines => json_lines(rng, &data, seeds),
            Format::Toml => text(rng, &data, seeds, Flavor::Toml),
            Format::Obj => text(rng, &data, seeds, Flavor::Obj),
            Format::Words => text(rng, &data, seeds, Flavor::Words),
            Format::Png => binary::png(rng, &data),
            Format::Glb => binary::glb(rng, &data),
        };
        if next.len() <= MAX_LEN {
            data = next;
        }
    }
    data
}

/// The dialect of a text, for its special values and wrong types.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Flavor {
    Json,
    Toml,
    Obj,
    Words,
}

impl Flavor {
    /// Numbers that break naive code ([`dictionary`]).
    fn specials(self) -> &'static [&'static str] {
        match self {
            Flavor::Json => dictionary::JSON_NUMBERS,
            Flavor::Toml => dictionary::TOML_NUMBERS,
            Flavor::Obj | Flavor::Words => dictionary::WORD_NUMBERS,
        }
    }

    /// Values of the wrong type for a number or a string.
    fn wrong_types(self) -> &'static [&'static str] {
        match self {
            Flavor::Json => dictionary::JSON_WRONG_TYPES,
            Flavor::Toml => dictionary::TOML_WRONG_TYPES,
            Flavor::Obj | Flavor::Words => dictionary::WORD_WRONG_TYPES,
        }
    }

    /// Whole lines a file of this dialect may hold, good or bad.
    fn lines(self) -> &'static [&'static str] {
        match self {
            Flavor::Json => dictionary::JSON_LINES,
            Flavor::Toml => dictionary::TOML_LINES,
            Flavor::Obj => dictionary::OBJ_LINES,
            Flavor::Words => dictionary::WORD_LINES,
        }
    }
}

/// Kinds of token a text is cut into.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Tok {
    Num,
    Str,
    Word,
    Punct,
    Space,
}

/// The text's tokens as (kind, byte range).
fn tokens(b: &[u8]) -> Vec<(Tok, std::ops::Range<usize>)> {
    let mut out = Vec::new();
    let mut i = 0;
    let is_num_char = |c: u8| c.is_ascii_alphanumeric() || matches!(c, b'.' | b'_' | b'+' | b'-');
    while i < b.len() {
        let c = b[i];
        let start = i;
        let next_digit = b
            .get(i + 1)
            .is_some_and(|d| d.is_ascii_digit() || *d == b'.');
        let kind = if c.is_ascii_digit() || (matches!(c, b'-' | b'+' | b'.') && next_digit) {
            i += 1;
            while i < b.len() && is_num_char(b[i]) {
                i += 1;
            }
            Tok::Num
        } else if c == b'"' || c == b'\'' {
            i += 1;
            while i < b.len() && b[i] != c && b[i] != b'\n' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i = (i + 1).min(b.len());
            Tok::Str
        } else if c.is_ascii_alphabetic() || c == b'_' {
            while i < b.len() && (b[i].is_ascii_alphanumeric() || matches!(b[i], b'_' | b'-')) {
                i += 1;
            }
            Tok::Word
        } else if c.is_ascii_whitespace() {
            while i < b.len() && b[i].is_ascii_whitespace() {
                i += 1;
            }
            Tok::Space
        } else {
            i += 1;
            Tok::Punct
        };
        out.push((kind, start..i));
    }
    out
}

fn splice(b: &[u8], range: std::ops::Range<usize>, with: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(b.len() + with.len());
    out.extend_from_slice(&b[..range.start]);
    out.extend_from_slice(with);
    out.extend_from_slice(&b[range.end..]);
    out
}

/// The byte ranges of the lines (without their newline).
fn lines(b: &[u8]) -> Vec<std::ops::Range<usize>> {
    let mut out = Vec::new();
    let mut start = 0;
    for (i, &c) in b.iter().enumerate() {
        if c == b'\n' {
            out.push(start..i);
            start = i + 1;
        }
    }
    if start < b.len() {
        out.push(start..b.len());
    }
    out
}

/// A random number of some size and sign, as text.
fn random_number(rng: &mut Rng) -> String {
    match rng.below(4) {
        0 => format!("{}", rng.next() as i64),
        1 => format!("{}e{}", rng.below(10), rng.below(800) as i64 - 400),
        2 => format!("{:.3}", (rng.next() % 2_000_000) as f64 / 1000.0 - 1000.0),
        _ => format!("{}", rng.below(5) as i64 - 2),
    }
}

/// A text cut into tokens and lines, for one mutation.
struct Cut<'a> {
    b: &'a [u8],
    toks: Vec<(Tok, std::ops::Range<usize>)>,
    lines: Vec<std::ops::Range<usize>>,
}

impl Cut<'_> {
    fn of(&self, kinds: &[Tok]) -> Vec<std::ops::Range<usize>> {
        self.toks
            .iter()
            .filter(|(k, _)| kinds.contains(k))
            .map(|(_, r)| r.clone())
            .collect()
    }
}

/// One token- or line-level mutation of a text (a blind byte mutation when the text has
/// nothing of the kind drawn).
pub fn text(rng: &mut Rng, b: &[u8], seeds: &[Vec<u8>], flavor: Flavor) -> Vec<u8> {
    let cut = Cut {
        b,
        toks: tokens(b),
        lines: lines(b),
    };
    let mutated = match rng.below(16) {
        0..=3 => new_number(rng, &cut, flavor),
        4 | 5 => wrong_type(rng, &cut, flavor),
        6..=8 => line_edit(rng, &cut),
        9 => token_edit(rng, &cut),
        10 => Some(b[..rng.below(b.len().max(1))].to_vec()),
        11 => Some(deep_nest(rng, &cut, flavor)),
        12 => new_string(rng, &cut),
        13 => Some(add_line(rng, &cut, seeds, flavor)),
        14 => word_swap(rng, &cut),
        _ => None,
    };
    mutated.unwrap_or_else(|| super::binary::bytes(rng, b))
}

/// A number replaced by a special one or a random one.
fn new_number(rng: &mut Rng, cut: &Cut, flavor: Flavor) -> Option<Vec<u8>> {
    let nums = cut.of(&[Tok::Num]);
    let r = nums.get(rng.below(nums.len().max(1)))?.clone();
    let with = if rng.chance(0.7) {
        rng.pick(flavor.specials()).to_string()
    } else {
        random_number(rng)
    };
    Some(splice(cut.b, r, with.as_bytes()))
}

/// A number or a string replaced by a value of another type.
fn wrong_type(rng: &mut Rng, cut: &Cut, flavor: Flavor) -> Option<Vec<u8>> {
    let values = cut.of(&[Tok::Num, Tok::Str]);
    let r = values.get(rng.below(values.len().max(1)))?.clone();
    Some(splice(cut.b, r, rng.pick(flavor.wrong_types()).as_bytes()))
}

/// A line deleted, repeated (up to thousands of times) or swapped with another.
fn line_edit(rng: &mut Rng, cut: &Cut) -> Option<Vec<u8>> {
    let b = cut.b;
    let r = cut.lines.get(rng.below(cut.lines.len().max(1)))?.clone();
    match rng.below(3) {
        0 => Some(splice(b, r.start..(r.end + 1).min(b.len()), b"")),
        1 => {
            // As many as asked for, within the size an input may grow to.
            let copies = (*rng.pick(&[1, 2, 10, 1000, 5_000])).min(MAX_LEN / (r.len() + 1));
            let mut line = b[r.clone()].to_vec();
            line.push(b'\n');
            Some(splice(b, r.start..r.start, &line.repeat(copies)))
        }
        _ => {
            let other = rng.pick(&cut.lines).clone();
            let (a, c) = if r.start <= other.start {
                (r, other)
            } else {
                (other, r)
            };
            if a.end >= c.start {
                return None;
            }
            let mut out = b[..a.start].to_vec();
            out.extend_from_slice(&b[c.clone()]);
            out.extend_from_slice(&b[a.end..c.start]);
            out.extend_from_slice(&b[a]);
            out.extend_from_slice(&b[c.end..]);
            Some(out)
        }
    }
}

/// A token deleted or doubled.
fn token_edit(rng: &mut Rng, cut: &Cut) -> Option<Vec<u8>> {
    let (_, r) = cut.toks.get(rng.below(cut.toks.len().max(1)))?.clone();
    if rng.chance(0.5) {
        Some(splice(cut.b, r, b""))
    } else {
        let t = cut.b[r.clone()].to_vec();
        Some(splice(cut.b, r.start..r.start, &t))
    }
}

/// A value (or the start) wrapped in arrays or tables nested up to 100 000 deep.
fn deep_nest(rng: &mut Rng, cut: &Cut, flavor: Flavor) -> Vec<u8> {
    let values = cut.of(&[Tok::Num, Tok::Str]);
    let at = values
        .get(rng.below(values.len().max(1)))
        .cloned()
        .unwrap_or(0..0);
    let depth = *rng.pick(&[16, 200, 5_000, 100_000]);
    let (open, close) = match (flavor, rng.below(2)) {
        (Flavor::Toml, 1) => ("{a=", "}"),
        (Flavor::Json, 1) => ("{\"a\":", "}"),
        _ => ("[", "]"),
    };
    let inner = if at.is_empty() {
        b"1".to_vec()
    } else {
        cut.b[at.clone()].to_vec()
    };
    let mut with = open.repeat(depth).into_bytes();
    with.extend_from_slice(&inner);
    with.extend_from_slice(close.repeat(depth).as_bytes());
    splice(cut.b, at, &with)
}

/// A string replaced by a NUL, a line break, odd Unicode, a device path or 100 000
/// characters.
fn new_string(rng: &mut Rng, cut: &Cut) -> Option<Vec<u8>> {
    let strs = cut.of(&[Tok::Str]);
    let r = strs.get(rng.below(strs.len().max(1)))?.clone();
    let with: Vec<u8> = match rng.below(5) {
        0 => b"\"\\u0000\"".to_vec(),
        1 => b"\"line\\nbreak\"".to_vec(),
        2 => "\"\u{1F600}\u{202E}\"".as_bytes().to_vec(),
        3 => b"\"/dev/null\"".to_vec(),
        _ => format!("\"{}\"", "x".repeat(100_000)).into_bytes(),
    };
    Some(splice(cut.b, r, &with))
}

/// A line of the dialect's own, or of another seed, inserted.
fn add_line(rng: &mut Rng, cut: &Cut, seeds: &[Vec<u8>], flavor: Flavor) -> Vec<u8> {
    let other: &[u8] = match seeds {
        [] => b"",
        _ => rng.pick(seeds).as_slice(),
    };
    let other_lines = lines(other);
    let at = cut
        .lines
        .get(rng.below(cut.lines.len().max(1)))
        .map_or(0, |r| r.start);
    let mut line = if other_lines.is_empty() || rng.chance(0.5) {
        rng.pick(flavor.lines()).as_bytes().to_vec()
    } else {
        other[rng.pick(&other_lines).clone()].to_vec()
    };
    line.push(b'\n');
    splice(cut.b, at..at, &line)
}

/// A word (a key) replaced by another of the text's, or misspelt.
fn word_swap(rng: &mut Rng, cut: &Cut) -> Option<Vec<u8>> {
    let words = cut.of(&[Tok::Word]);
    let r = words.get(rng.below(words.len().max(1)))?.clone();
    let with = if rng.chance(0.5) {
        cut.b[rng.pick(&words).clone()].to_vec()
    } else {
        let mut w = cut.b[r.clone()].to_vec();
        w.pop();
        w
    };
    Some(splice(cut.b, r, &with))
}

/// Mutates a JSON document as a tree: the result parses as JSON unless a raw special (NaN,
/// 1e999, deep nesting) is written in. None if `b` is not JSON.
pub fn json_tree(rng: &mut Rng, b: &[u8]) -> Option<Vec<u8>> {
    let mut doc: Value = serde_json::from_slice(b).ok()?;
    let mut paths = Vec::new();
    collect_paths(&doc, String::new(), &mut paths);
    let path = rng.pick(&paths).clone();
    let mut raw: Option<String> = None;
    let node = doc.pointer_mut(&path)?;
    match rng.below(9) {
        0 | 1 => raw = Some(rng.pick(Flavor::Json.specials()).to_string()),
        2 => {
            *node = match node {
                Value::Number(n) => Value::String(n.to_string()),
                Value::String(s) => s
                    .parse::<f64>()
                    .map(Value::from)
                    .unwrap_or(Value::Bool(true)),
                Value::Array(_) => serde_json::json!({}),
                Value::Object(_) => serde_json::json!([]),
                _ => serde_json::json!(1),
            }
        }
        3 => *node = Value::Null,
        4 => match node {
            Value::Object(map) if !map.is_empty() => {
                let key = map.keys().nth(rng.below(map.len()))?.clone();
                map.remove(&key);
            }
            Value::Array(items) if !items.is_empty() => {
                items.remove(rng.below(items.len()));
            }
            _ => *node = serde_json::json!([]),
        },
        5 => match node {
            Value::Array(items) if !items.is_empty() => {
                let item = items[rng.below(items.len())].clone();
                let size = item.to_string().len() + 1;
                let copies = (*rng.pick(&[1, 3, 100, 5_000])).min(MAX_LEN / size);
                items.extend(std::iter::repeat_n(item, copies));
            }
            Value::Object(map) => {
                map.insert("unknown_key".into(), serde_json::json!(1));
            }
            _ => raw = Some(format!("{}{}", "[".repeat(1000), "]".repeat(1000))),
        },
        6 => {
            let depth = *rng.pick(&[10, 130, 5_000]);
            let inner = node.to_string();
            raw = Some(format!("{}{inner}{}", "[".repeat(depth), "]".repeat(depth)));
        }
        7 => raw = Some(random_number(rng)),
        _ => {
            *node = match rng.below(4) {
                0 => Value::from(u32::MAX),
                1 => Value::from(0),
                2 => Value::from(-1),
                _ => Value::from(u64::MAX),
            }
        }
    }
    const MARK: &str = "@@fuzz-raw@@";
    if raw.is_some() {
        *doc.pointer_mut(&path)? = Value::String(MARK.into());
    }
    let text = if rng.chance(0.5) {
        serde_json::to_string_pretty(&doc).ok()?
    } else {
        serde_json::to_string(&doc).ok()?
    };
    Some(match raw {
        Some(raw) => text.replacen(&format!("\"{MARK}\""), &raw, 1).into_bytes(),
        None => text.into_bytes(),
    })
}

/// JSON pointers of every node of `v` (the root is "").
fn collect_paths(v: &Value, at: String, out: &mut Vec<String>) {
    match v {
        Value::Object(map) => {
            for (k, item) in map {
                let key = k.replace('~', "~0").replace('/', "~1");
                collect_paths(item, format!("{at}/{key}"), out);
            }
        }
        Value::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                collect_paths(item, format!("{at}/{i}"), out);
            }
        }
        _ => {}
    }
    out.push(at);
}

/// One mutation of a JSON-lines file: a line mutated as JSON, or lines deleted, duplicated,
/// swapped, torn or added.
pub fn json_lines(rng: &mut Rng, b: &[u8], seeds: &[Vec<u8>]) -> Vec<u8> {
    let ls = lines(b);
    if ls.is_empty() || rng.chance(0.3) {
        return text(rng, b, seeds, Flavor::Json);
    }
    let r = rng.pick(&ls).clone();
    let line = &b[r.clone()];
    let with = match rng.below(4) {
        0 | 1 => json_tree(rng, line).unwrap_or_else(|| text(rng, line, seeds, Flavor::Json)),
        2 => text(rng, line, seeds, Flavor::Json),
        _ => line[..rng.below(line.len().max(1))].to_vec(),
    };
    // A mutated line stays one line unless the mutation wrote a newline in on purpose.
    let with: Vec<u8> = if rng.chance(0.9) {
        with.into_iter().filter(|&c| c != b'\n').collect()
    } else {
        with
    };
    splice(b, r, &with)
}
