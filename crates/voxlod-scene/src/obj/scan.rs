//! Line-by-line validation of OBJ and MTL text before tobj sees it.
//!
//! tobj reports errors without a line number, accepts `nan`/`inf` coordinates, panics on an MTL
//! colour with fewer than three numbers, overflows on huge face indices, and reads `l` polylines
//! as polygons. This pass rejects every malformed line with its number, and produces the
//! normalized text tobj parses: leading whitespace removed, `l`/`p` elements dropped (counted),
//! and every `mtllib` moved to the top so that a `usemtl` may precede the library defining it.

use std::borrow::Cow;
use std::path::Path;

use crate::{Error, Result};

/// What the scan learnt about an OBJ file.
#[derive(Debug, Default)]
pub(super) struct ObjScan {
    /// `mtllib` file names with their line numbers, in file order.
    pub mtllibs: Vec<(usize, String)>,
    /// Material names used by `usemtl`, in file order.
    pub usemtls: Vec<String>,
    /// `l` (polyline) elements dropped.
    pub polylines: usize,
    /// `p` (point) elements dropped.
    pub points: usize,
    /// The text tobj should parse.
    pub normalized: String,
}

fn bad(path: &Path, line: usize, reason: impl std::fmt::Display) -> Error {
    Error::Obj { path: path.to_owned(), reason: format!("line {line}: {reason}") }
}

/// The name given to a material whose `newmtl` or `usemtl` has no name (Blender writes
/// `usemtl ` for an unnamed material); tobj rejects empty names.
pub(super) const UNNAMED: &str = "(unnamed)";

/// Decodes a file's bytes as text: UTF-8 (a leading byte-order mark is dropped), else
/// Latin-1, the legacy encoding of many OBJ/MTL exporters (each byte one character, so the
/// same names decode the same way in the OBJ and its MTL). UTF-16 is an error.
pub(super) fn text<'a>(path: &Path, bytes: &'a [u8]) -> Result<Cow<'a, str>> {
    if bytes.starts_with(&[0xFE, 0xFF]) || bytes.starts_with(&[0xFF, 0xFE]) {
        return Err(bad(
            path,
            1,
            "UTF-16 text (byte-order mark); only UTF-8, ASCII or Latin-1 is supported",
        ));
    }
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    Ok(match std::str::from_utf8(bytes) {
        Ok(text) => Cow::Borrowed(text),
        Err(_) => Cow::Owned(bytes.iter().map(|&b| char::from(b)).collect()),
    })
}

/// Parses `n` finite numbers from `words`, naming the keyword on failure.
fn numbers<'a>(
    words: &mut impl Iterator<Item = &'a str>,
    n: usize,
    keyword: &str,
) -> std::result::Result<Vec<f32>, String> {
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let Some(w) = words.next() else {
            return Err(format!("'{keyword}' needs {n} numbers, found {k}"));
        };
        let x: f32 = w.parse().map_err(|_| format!("'{keyword}': '{w}' is not a number"))?;
        if !x.is_finite() {
            return Err(format!("'{keyword}': {w} is not a finite number"));
        }
        out.push(x);
    }
    Ok(out)
}

/// Checks one face corner `v[/vt[/vn]]` against the element counts: `so_far` (defined before
/// this line, for negative indices) and `total` (in the whole file, for positive ones).
fn corner(word: &str, so_far: [usize; 3], total: [usize; 3]) -> std::result::Result<(), String> {
    const NAMES: [&str; 3] = ["vertex", "texture coordinate", "normal"];
    let parts: Vec<&str> = word.split('/').collect();
    if parts.len() > 3 || parts[0].is_empty() {
        return Err(format!("face corner '{word}' is not v, v/vt, v//vn or v/vt/vn"));
    }
    for (k, part) in parts.iter().enumerate().filter(|(_, p)| !p.is_empty()) {
        let i: i64 =
            part.parse().map_err(|_| format!("face corner '{word}': '{part}' is not an index"))?;
        let (what, have) = (NAMES[k], if i < 0 { so_far[k] } else { total[k] });
        if i == 0 {
            return Err(format!("face corner '{word}': {what} index 0 (OBJ counts from 1)"));
        }
        if i.unsigned_abs() > have as u64 {
            let scope = if i < 0 { "defined so far" } else { "in the file" };
            return Err(format!(
                "face corner '{word}' refers to {what} {i}, but there are {have} {scope}"
            ));
        }
    }
    Ok(())
}

/// Validates an OBJ file and returns its normalized text.
pub(super) fn scan_obj(path: &Path, text: &str) -> Result<ObjScan> {
    let mut total = [0usize; 3];
    for line in text.lines() {
        match line.split_whitespace().next() {
            Some("v") => total[0] += 1,
            Some("vt") => total[1] += 1,
            Some("vn") => total[2] += 1,
            _ => {}
        }
    }
    let mut scan =
        ObjScan { normalized: String::with_capacity(text.len() + 64), ..Default::default() };
    let mut body = String::with_capacity(text.len());
    let mut so_far = [0usize; 3];
    for (n, line) in text.lines().enumerate().map(|(i, l)| (i + 1, l.trim())) {
        let mut words = line.split_whitespace();
        let keyword = words.next().unwrap_or("");
        let rest = line[keyword.len()..].trim();
        let check = |r: std::result::Result<(), String>| r.map_err(|e| bad(path, n, e));
        match keyword {
            "v" => {
                let xyz = numbers(&mut words, 3, "v").map_err(|e| bad(path, n, e))?;
                let extra: Vec<&str> = words.collect();
                match extra.len() {
                    0 | 3 => {}
                    1 => {
                        let w: f32 = extra[0]
                            .parse()
                            .map_err(|_| bad(path, n, format!("'v': w = '{}'", extra[0])))?;
                        let scaled = xyz.iter().map(|c| c / w);
                        if w == 0.0 || !w.is_finite() || !scaled.clone().all(f32::is_finite) {
                            return Err(bad(path, n, format!("'v': weight w = {w} is unusable")));
                        }
                    }
                    k => return Err(bad(path, n, format!("'v' has {} values (3, 4 or 6)", 3 + k))),
                }
                so_far[0] += 1;
            }
            "vt" => {
                check(numbers(&mut words, 2, "vt").map(drop))?;
                so_far[1] += 1;
            }
            "vn" => {
                check(numbers(&mut words, 3, "vn").map(drop))?;
                so_far[2] += 1;
            }
            "f" => {
                if rest.is_empty() {
                    return Err(bad(path, n, "face without vertices"));
                }
                for w in words {
                    check(corner(w, so_far, total))?;
                }
            }
            "l" | "p" => {
                if keyword == "l" {
                    scan.polylines += 1
                } else {
                    scan.points += 1
                }
                body.push('\n');
                continue;
            }
            "mtllib" => {
                if rest.is_empty() {
                    return Err(bad(path, n, "'mtllib' without a file name"));
                }
                scan.mtllibs.push((n, rest.to_owned()));
                body.push('\n');
                continue;
            }
            "usemtl" => {
                let name = if rest.is_empty() { UNNAMED } else { rest };
                scan.usemtls.push(name.to_owned());
                body.push_str("usemtl ");
                body.push_str(name);
                body.push('\n');
                continue;
            }
            "o" | "g" => {
                body.push_str(keyword);
                body.push(' ');
                body.push_str(rest);
                body.push('\n');
                continue;
            }
            _ => {}
        }
        body.push_str(line);
        body.push('\n');
    }
    for (_, name) in &scan.mtllibs {
        scan.normalized.push_str("mtllib ");
        scan.normalized.push_str(name);
        scan.normalized.push('\n');
    }
    scan.normalized.push_str(&body);
    Ok(scan)
}

/// Validates an MTL file line by line (tobj panics on a colour with fewer than three numbers)
/// and returns the text tobj should parse (an unnamed `newmtl` is named [`UNNAMED`]).
pub(super) fn scan_mtl(path: &Path, text: &str) -> Result<String> {
    let mut out = String::with_capacity(text.len());
    for (n, line) in text.lines().enumerate().map(|(i, l)| (i + 1, l.trim())) {
        let mut words = line.split_whitespace();
        let keyword = words.next().unwrap_or("");
        if keyword == "newmtl" && words.clone().next().is_none() {
            out.push_str("newmtl ");
            out.push_str(UNNAMED);
            out.push('\n');
            continue;
        }
        let colour = matches!(keyword, "Ka" | "Kd" | "Ks" | "Ke");
        if colour && words.clone().count() == 1 {
            // "Ks r" means r r r (the MTL specification makes g and b optional).
            let r = numbers(&mut words.clone(), 1, keyword).map_err(|e| bad(path, n, e))?[0];
            out.push_str(&format!("{keyword} {r} {r} {r}\n"));
            continue;
        }
        out.push_str(line);
        out.push('\n');
        let check =
            |r: std::result::Result<Vec<f32>, String>| r.map(drop).map_err(|e| bad(path, n, e));
        match keyword {
            "Ka" | "Kd" | "Ks" | "Ke" => check(numbers(&mut words, 3, keyword))?,
            "Ns" | "Ni" | "d" | "Tr" => check(numbers(&mut words, 1, keyword))?,
            "illum" => {
                let w = words.next().unwrap_or("");
                if w.parse::<u8>().is_err() {
                    return Err(bad(path, n, format!("'illum {w}': expected an integer 0–255")));
                }
            }
            "map_Ka" | "map_Kd" | "map_Ks" | "map_Ns" | "map_ns" | "map_NS" | "map_d"
            | "map_Bump" | "map_bump" | "bump"
                if words.next().is_none() =>
            {
                return Err(bad(path, n, format!("'{keyword}' without a name")));
            }
            _ => {}
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn obj_err(text: &str) -> String {
        scan_obj(Path::new("t.obj"), text).unwrap_err().to_string()
    }

    #[test]
    fn bad_lines_are_named() {
        let v = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        for (text, expect) in [
            (format!("{v}f 1 2 4\n"), "line 4: face corner '4' refers to vertex 4"),
            (format!("{v}f 1 2 0\n"), "line 4: face corner '0': vertex index 0"),
            (format!("{v}f 1 -4 2\n"), "line 4: face corner '-4' refers to vertex -4"),
            (format!("{v}f 1/1 2/1 3/1\n"), "refers to texture coordinate 1, but there are 0"),
            (format!("{v}f 1 2 3/x\n"), "'x' is not an index"),
            (format!("{v}f\n"), "line 4: face without vertices"),
            (format!("{v}f 1 2 99999999999999999999\n"), "is not an index"),
            ("v 0 nan 0\n".to_owned(), "line 1: 'v': nan is not a finite number"),
            ("v 1e39 0 0\n".to_owned(), "line 1: 'v': 1e39 is not a finite number"),
            ("v 0 0\n".to_owned(), "line 1: 'v' needs 3 numbers, found 2"),
            ("v 0 0 0 0\n".to_owned(), "weight w = 0"),
            ("v 0 0 0 1 1\n".to_owned(), "'v' has 5 values"),
            ("vn 0 0 inf\n".to_owned(), "not a finite number"),
            ("vt 3.1+e2 0\n".to_owned(), "'3.1+e2' is not a number"),
            ("mtllib\n".to_owned(), "'mtllib' without a file name"),
        ] {
            let err = obj_err(&text);
            assert!(err.contains("t.obj") && err.contains(expect), "{text:?}: {err}");
        }
    }

    #[test]
    fn forward_references_and_relative_indices_are_accepted() {
        // Positive indices may refer to vertices defined later (tobj accepts them); negative
        // ones count back from the current line.
        let scan = scan_obj(Path::new("t.obj"), "f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n");
        assert!(scan.is_ok());
    }

    #[test]
    fn normalization_moves_mtllibs_up_and_drops_polylines() {
        let text = "  g a\nusemtl\tM\nl 1 2 3\np 1\nmtllib m.mtl\nv 0 0 0\n";
        let scan = scan_obj(Path::new("t.obj"), text).unwrap();
        assert_eq!(scan.mtllibs, vec![(5, "m.mtl".to_owned())]);
        assert_eq!((scan.polylines, scan.points), (1, 1));
        assert_eq!(scan.normalized, "mtllib m.mtl\ng a\nusemtl M\n\n\n\nv 0 0 0\n");
    }

    #[test]
    fn mtl_lines_that_would_panic_tobj_are_errors() {
        for (text, expect) in [
            ("newmtl a\nKd 1 1\n", "line 2: 'Kd' needs 3 numbers, found 2"),
            ("newmtl a\nKd spectral x.rfl\n", "line 2: 'Kd': 'spectral' is not a number"),
            ("newmtl a\nKs 1 1 nan\n", "line 2: 'Ks': nan is not a finite number"),
            ("newmtl a\nd\n", "'d' needs 1 numbers, found 0"),
            ("newmtl a\nillum 300\n", "'illum 300'"),
        ] {
            let err = scan_mtl(Path::new("m.mtl"), text).unwrap_err().to_string();
            assert!(err.contains("m.mtl") && err.contains(expect), "{text:?}: {err}");
        }
        let text = scan_mtl(
            Path::new("m.mtl"),
            "newmtl a\nKd 1 0.5 0\nmap_Kd -s 2 2 t.png\nnewmtl\nKs 0.5",
        );
        assert_eq!(
            text.unwrap(),
            "newmtl a\nKd 1 0.5 0\nmap_Kd -s 2 2 t.png\nnewmtl (unnamed)\nKs 0.5 0.5 0.5\n"
        );
    }

    #[test]
    fn utf16_is_an_error_and_latin1_is_decoded() {
        let err = text(Path::new("t.obj"), b"\xFE\xFF\x00v").unwrap_err().to_string();
        assert!(err.contains("t.obj: line 1: UTF-16"), "{err}");
        assert_eq!(text(Path::new("t.obj"), b"usemtl Terraind\xE6k").unwrap(), "usemtl Terraindæk");
        assert_eq!(text(Path::new("t.obj"), b"\xEF\xBB\xBFv 0 0 0").unwrap(), "v 0 0 0");
    }
}
