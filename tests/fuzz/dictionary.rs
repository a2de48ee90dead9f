//! The fuzz mutations' dictionary: special numbers, values of the wrong type and whole
//! lines, by dialect. Tables of data, kept one row per line.
#![cfg_attr(rustfmt, rustfmt::skip)]

/// Numbers that break naive code: non-finite, huge, tiny, negative, zero, -0, past the
/// integer types' ends, and spellings a parser may or may not take.
pub const JSON_NUMBERS: &[&str] = &[
    "NaN", "Infinity", "-Infinity", "1e999", "-1e999", "1e308", "-1e308", "0", "-0", "-0.0",
    "-1", "5e-324", "1e-400", "18446744073709551616", "-9223372036854775809", "4294967295",
    "4294967296", "2147483648", "1.7976931348623157e308", "0.1", "1e30",
    "123456789012345678901234567890", "01", ".5", "+1", "0x10", "1e", "-",
];
pub const TOML_NUMBERS: &[&str] = &[
    "nan", "+nan", "-nan", "inf", "-inf", "+inf", "1e308", "-1e308", "1e999", "0", "0.0",
    "-0.0", "-0", "-1", "-1.0", "5e-324", "9223372036854775807", "-9223372036854775808",
    "9223372036854775808", "4294967296", "1e30", "1e-30", "1_000", "0x7fffffff", "0o777",
    "0b1", "1979-05-27", "1.", ".5", "1e",
];
pub const WORD_NUMBERS: &[&str] = &[
    "nan", "NaN", "inf", "-inf", "infinity", "1e38", "3.5e38", "-3.5e38", "1e308", "1e999",
    "0", "-0", "-0.0", "-1", "1e-45", "1e-320", "2147483648", "4294967295", "4294967296",
    "-2147483649", "99999999999", "18446744073709551616", "0.5", "", "1e", "--1", "0x10", "1,5",
];

/// Values of the wrong type for a number or a string.
pub const JSON_WRONG_TYPES: &[&str] = &[
    "\"1\"", "\"\"", "true", "null", "[]", "{}", "[1, 2, 3]", "{\"a\": 1}", "\"rotation=30\"",
];
pub const TOML_WRONG_TYPES: &[&str] = &[
    "\"1\"", "\"\"", "true", "[]", "{}", "[1, 2, 3]", "{ a = 1 }", "1979-05-27T07:32:00Z",
    "\"rotation=30\"", "[[1], [\"a\"]]",
];
pub const WORD_WRONG_TYPES: &[&str] = &["x", "1/2/3", "#", "\\", "=", "rotation=", "1 2"];

/// Whole lines a file of the dialect may hold, good or bad.
pub const JSON_LINES: &[&str] = &["{", "}", "[", "]", ",", "\"contacts\": []", "null"];
pub const TOML_LINES: &[&str] = &[
    "[finger]", "[lens]", "[image]", "[render]", "[[contacts]]", "[contacts]",
    "width = 4294967296", "height = 0", "heightfield_texels = 4096", "ray_steps = 256",
    "model = \"pinhole\"", "k = [1.0, -1.0, 1.0, -1.0]", "object = \"sphere\"",
    "at = { rotation = 1e300 }", "pose = []", "a.b.c = 1", "x = 1\nx = 2",
];
pub const OBJ_LINES: &[&str] = &[
    "f 1 2 3 4 5 6 7 8 9 10", "f 1 2", "f 0 0 0", "f -1 -2 -3", "f 1/1/1 2//2 3/3",
    "f 4294967295 1 2", "v 1e38 1e38 1e38", "v nan 0 0", "v 1 2", "v 1 2 3 4 5 6 7",
    "vn 0 0 1", "vt 0.5", "o part", "g a b c", "s off", "mtllib missing.mtl", "usemtl none",
    "l 1 2", "p 1", "#", "\\",
];
pub const WORD_LINES: &[&str] = &[",", " ", "=", "rotation", "s", "translation"];
