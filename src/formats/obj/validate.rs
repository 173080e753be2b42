//! Line-by-line checks of OBJ text before tobj parses it, so that every malformed
//! statement is reported with its file and line (tobj reports only a kind of error), and so that
//! non-finite numbers, which Rust's float parser accepts as "nan" or "inf", are refused.

use crate::error::{Error, Result};
use std::path::Path;

fn floats(path: &Path, line_no: usize, what: &str, words: &[&str], min: usize, max: usize) -> Result<Vec<f32>> {
    if words.len() < min || words.len() > max {
        let count = if min == max { format!("{min}") } else { format!("{min} to {max}") };
        return Err(Error::parse(path, line_no, format!("`{what}` needs {count} numbers, found {}", words.len())));
    }
    words.iter().map(|w| number(path, line_no, what, w)).collect()
}

/// The word `w` of statement `what` as a finite number (Rust's parser alone accepts "nan" and
/// "inf"), or an error naming the file and line.
pub(super) fn number(path: &Path, line: usize, what: &str, w: &str) -> Result<f32> {
    let v: f32 = w.parse().map_err(|_| Error::parse(path, line, format!("`{what}`: `{w}` is not a number")))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::parse(path, line, format!("`{what}`: `{w}` is not finite")))
    }
}

/// An `mtllib` statement: its line and what follows the keyword (one or more file names).
#[derive(Clone, Debug, PartialEq)]
pub struct MtlLib {
    /// 1-based line.
    pub line: usize,
    /// The rest of the line, trimmed.
    pub names: String,
}

/// Checks an OBJ file's text; returns its `mtllib` statements.
pub fn check_obj(path: &Path, text: &str) -> Result<Vec<MtlLib>> {
    let mut n_v = 0i64;
    let mut n_vt = 0i64;
    let mut n_vn = 0i64;
    let mut n_f = 0usize;
    let mut mtllibs = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = raw.split('#').next().unwrap_or("").trim();
        let mut it = line.split_whitespace();
        let Some(kw) = it.next() else { continue };
        let words: Vec<&str> = it.collect();
        match kw {
            "v" => {
                // x y z [w], optionally followed by r g b vertex colours.
                floats(path, line_no, "v", &words, 3, 7)?;
                n_v += 1;
            }
            "vn" => {
                floats(path, line_no, "vn", &words, 3, 3)?;
                n_vn += 1;
            }
            "vt" => {
                floats(path, line_no, "vt", &words, 1, 3)?;
                n_vt += 1;
            }
            "f" => {
                if words.len() < 3 {
                    return Err(Error::parse(
                        path,
                        line_no,
                        format!("a face needs at least 3 vertices, found {}", words.len()),
                    ));
                }
                for w in &words {
                    for (k, part) in w.split('/').enumerate() {
                        if part.is_empty() && k > 0 {
                            continue;
                        }
                        let (count, what) = match k {
                            0 => (n_v, "vertex"),
                            1 => (n_vt, "texture coordinate"),
                            2 => (n_vn, "normal"),
                            _ => {
                                return Err(Error::parse(
                                    path,
                                    line_no,
                                    format!("face vertex `{w}` has too many `/` parts"),
                                ))
                            }
                        };
                        let idx: i64 = part.parse().map_err(|_| {
                            Error::parse(path, line_no, format!("face vertex `{w}`: `{part}` is not an index"))
                        })?;
                        let resolved = if idx < 0 { count + idx + 1 } else { idx };
                        if idx == 0 || resolved < 1 || resolved > count {
                            return Err(Error::parse(
                                path,
                                line_no,
                                format!("face refers to {what} {idx}, but only {count} are defined before this line"),
                            ));
                        }
                    }
                }
                n_f += 1;
            }
            "mtllib" => {
                let name = line.split_once(char::is_whitespace).map(|x| x.1.trim()).unwrap_or("");
                if name.is_empty() {
                    return Err(Error::parse(path, line_no, "`mtllib` names no file"));
                }
                mtllibs.push(MtlLib { line: line_no, names: name.to_string() });
            }
            "usemtl" | "o" | "g" | "s" | "l" | "p" | "vp" | "cstype" | "deg" | "curv" | "surf" | "parm" | "end"
            | "usemap" | "maplib" | "mg" | "lod" | "bevel" | "c_interp" | "d_interp" | "shadow_obj" | "trace_obj"
            | "call" | "csh" => {}
            other => {
                return Err(Error::parse(path, line_no, format!("unknown OBJ statement `{other}`")));
            }
        }
    }
    if n_f == 0 {
        return Err(Error::parse(path, 0, "the file has no faces"));
    }
    Ok(mtllibs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reports_line_of_bad_vertex() {
        let e = check_obj(Path::new("a.obj"), "v 0 0 0\nv 1 nan 0\nf 1 2 1\n").unwrap_err();
        assert!(e.to_string().starts_with("a.obj:2:"), "{e}");
        let e = check_obj(Path::new("a.obj"), "v 0 0 0\nv 1 0 0\nf 1 2 3\n").unwrap_err();
        assert!(e.to_string().contains("a.obj:3:") && e.to_string().contains("vertex 3"), "{e}");
    }
}
