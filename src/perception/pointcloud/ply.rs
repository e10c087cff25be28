//! The PLY reader: [`parse_ply`], the header's elements and properties, and the vertices
//! of ASCII and binary little-endian data.

use super::{check_count_fits, finish, fmt_err, split_header, CloudError, PointCloud, Scalar};
use std::path::Path;

#[derive(Debug, Clone)]
enum PlyProp {
    Scalar { name: String, ty: Scalar },
    List { count: Scalar, item: Scalar },
}

#[derive(Debug, Clone)]
struct PlyElement {
    name: String,
    /// The header line that declares it.
    line: usize,
    count: usize,
    props: Vec<PlyProp>,
}

/// Parses PLY `bytes` read from `path` (used in error messages).
pub fn parse_ply(path: &Path, bytes: &[u8]) -> Result<PointCloud, CloudError> {
    let (header, data_start) = split_header(path, bytes, |l| l == "end_header", "end_header")?;
    if header.first().map(|h| h.1) != Some("ply") {
        return Err(fmt_err(path, Some(1), "file does not start with 'ply'"));
    }
    let mut binary: Option<bool> = None;
    let mut elements: Vec<PlyElement> = Vec::new();
    for &(no, line) in &header[1..] {
        let toks: Vec<&str> = line.split_whitespace().collect();
        match toks.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] | ["end_header"] => {}
            ["format", kind, version] => {
                if *version != "1.0" {
                    return Err(fmt_err(
                        path,
                        Some(no),
                        format!("unsupported PLY version '{version}' (1.0)"),
                    ));
                }
                binary = Some(match *kind {
                    "ascii" => false,
                    "binary_little_endian" => true,
                    other => {
                        return Err(fmt_err(
                            path,
                            Some(no),
                            format!(
                                "unsupported PLY format '{other}' (ascii or binary_little_endian)"
                            ),
                        ))
                    }
                })
            }
            ["element", name, count] => {
                let count = count.parse::<usize>().map_err(|_| {
                    fmt_err(
                        path,
                        Some(no),
                        format!("element {name}: '{count}' is not a count"),
                    )
                })?;
                elements.push(PlyElement {
                    name: name.to_string(),
                    line: no,
                    count,
                    props: Vec::new(),
                });
            }
            ["property", "list", cnt, item, _name] => {
                let e = elements
                    .last_mut()
                    .ok_or_else(|| fmt_err(path, Some(no), "property before any element"))?;
                let bad = |t: &str| fmt_err(path, Some(no), format!("unknown PLY type '{t}'"));
                let count = Scalar::ply(cnt).ok_or_else(|| bad(cnt))?;
                let item = Scalar::ply(item).ok_or_else(|| bad(item))?;
                if count.is_float() {
                    return Err(fmt_err(
                        path,
                        Some(no),
                        "list count type must be an integer",
                    ));
                }
                e.props.push(PlyProp::List { count, item });
            }
            ["property", ty, name] => {
                let e = elements
                    .last_mut()
                    .ok_or_else(|| fmt_err(path, Some(no), "property before any element"))?;
                let ty = Scalar::ply(ty)
                    .ok_or_else(|| fmt_err(path, Some(no), format!("unknown PLY type '{ty}'")))?;
                e.props.push(PlyProp::Scalar {
                    name: name.to_string(),
                    ty,
                });
            }
            _ => {
                return Err(fmt_err(
                    path,
                    Some(no),
                    format!("unrecognised PLY header line '{line}'"),
                ))
            }
        }
    }
    let binary = binary.ok_or_else(|| fmt_err(path, None, "header has no 'format' line"))?;
    let vi = elements
        .iter()
        .position(|e| e.name == "vertex")
        .ok_or_else(|| fmt_err(path, None, "header has no 'element vertex'"))?;
    let mut xyz = [0usize; 3];
    for (a, name) in ["x", "y", "z"].iter().enumerate() {
        let k = elements[vi]
            .props
            .iter()
            .position(|p| matches!(p, PlyProp::Scalar { name: n, .. } if n == name))
            .ok_or_else(|| fmt_err(path, None, format!("vertex has no property '{name}'")))?;
        if let PlyProp::Scalar { ty, .. } = elements[vi].props[k] {
            if !ty.is_float() {
                return Err(fmt_err(
                    path,
                    None,
                    format!("vertex property '{name}' must be float or double"),
                ));
            }
        }
        xyz[a] = k;
    }
    let data = &bytes[data_start..];
    // The elements read (those up to the vertices) must fit in the data: each binary
    // item takes its scalars and list counts, each text item a line.
    let mut need = 0usize;
    for e in &elements[..=vi] {
        let min = if binary {
            e.props
                .iter()
                .map(|p| match p {
                    PlyProp::Scalar { ty, .. } => ty.size(),
                    PlyProp::List { count, .. } => count.size(),
                })
                .sum::<usize>()
        } else {
            // A line of at least one character and its newline (a loose bound, so that a
            // short line still gets its own error).
            2
        };
        let what = format!("element {}", e.name);
        check_count_fits(
            path,
            Some(e.line),
            &what,
            e.count,
            min,
            data.len() - need.min(data.len()),
        )?;
        need = need.saturating_add(e.count.saturating_mul(min));
    }
    let raw = if binary {
        read_ply_binary(path, data, &elements, vi, xyz)?
    } else {
        let first_line = header.last().map(|h| h.0).unwrap_or(0) + 1;
        read_ply_ascii(path, data, first_line, &elements, vi, xyz)?
    };
    finish(path, raw)
}

fn read_ply_binary(
    path: &Path,
    data: &[u8],
    elements: &[PlyElement],
    vi: usize,
    xyz: [usize; 3],
) -> Result<Vec<[f64; 3]>, CloudError> {
    let mut pos = 0usize;
    let short = |what: &str, i: usize| {
        fmt_err(
            path,
            None,
            format!("binary data ends inside {what} {i}: the file is truncated"),
        )
    };
    let take = |pos: &mut usize, n: usize| -> Option<usize> {
        let start = *pos;
        let end = start.checked_add(n)?;
        (end <= data.len()).then(|| {
            *pos = end;
            start
        })
    };
    for e in &elements[..=vi] {
        let is_vertex = e.name == "vertex";
        let mut out = Vec::with_capacity(if is_vertex { e.count } else { 0 });
        for i in 0..e.count {
            let mut p = [0.0; 3];
            for (k, prop) in e.props.iter().enumerate() {
                match prop {
                    PlyProp::Scalar { ty, .. } => {
                        let s = take(&mut pos, ty.size()).ok_or_else(|| short(&e.name, i))?;
                        if is_vertex {
                            if let Some(a) = xyz.iter().position(|&x| x == k) {
                                p[a] = ty.read_le(&data[s..]);
                            }
                        }
                    }
                    PlyProp::List { count, item } => {
                        let s = take(&mut pos, count.size()).ok_or_else(|| short(&e.name, i))?;
                        let n = count.read_le(&data[s..]);
                        if n < 0.0 {
                            return Err(fmt_err(
                                path,
                                None,
                                format!("{} {i}: negative list length", e.name),
                            ));
                        }
                        let bytes = (n as usize).saturating_mul(item.size());
                        take(&mut pos, bytes).ok_or_else(|| short(&e.name, i))?;
                    }
                }
            }
            if is_vertex {
                out.push(p);
            }
        }
        if is_vertex {
            return Ok(out);
        }
    }
    Ok(Vec::new())
}

fn read_ply_ascii(
    path: &Path,
    data: &[u8],
    first_line: usize,
    elements: &[PlyElement],
    vi: usize,
    xyz: [usize; 3],
) -> Result<Vec<[f64; 3]>, CloudError> {
    let text = std::str::from_utf8(data)
        .map_err(|_| fmt_err(path, None, "ASCII data is not UTF-8 text"))?;
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (first_line + i, l.trim()))
        .filter(|(_, l)| !l.is_empty());
    for e in &elements[..=vi] {
        let is_vertex = e.name == "vertex";
        let mut out = Vec::with_capacity(if is_vertex { e.count } else { 0 });
        for i in 0..e.count {
            let (no, line) = lines.next().ok_or_else(|| {
                fmt_err(
                    path,
                    None,
                    format!(
                        "data ends at {} {i} of {}: the file is truncated",
                        e.name, e.count
                    ),
                )
            })?;
            if !is_vertex {
                continue;
            }
            let vals: Vec<&str> = line.split_whitespace().collect();
            // Vertex lines with list properties are rare; only scalar columns are read.
            if e.props.iter().any(|p| matches!(p, PlyProp::List { .. })) {
                return Err(fmt_err(
                    path,
                    Some(no),
                    "list properties on vertices are not supported",
                ));
            }
            if vals.len() != e.props.len() {
                return Err(fmt_err(
                    path,
                    Some(no),
                    format!(
                        "vertex {i}: expected {} values, found {}",
                        e.props.len(),
                        vals.len()
                    ),
                ));
            }
            let mut p = [0.0; 3];
            for a in 0..3 {
                let v = vals[xyz[a]];
                p[a] = v.parse::<f64>().map_err(|_| {
                    fmt_err(
                        path,
                        Some(no),
                        format!(
                            "vertex {i}, property {}: '{v}' is not a number",
                            ["x", "y", "z"][a]
                        ),
                    )
                })?;
            }
            out.push(p);
        }
        if is_vertex {
            return Ok(out);
        }
    }
    Ok(Vec::new())
}

#[cfg(test)]
mod tests {
    use super::super::tests::p;
    use super::*;
    use nalgebra::Point3;

    #[test]
    fn ply_ascii_and_binary_with_faces() {
        let text = "ply\nformat ascii 1.0\ncomment x\nelement vertex 3\nproperty float x\nproperty float y\n\
                    property double z\nproperty uchar red\nelement face 1\nproperty list uchar int vertex_indices\n\
                    end_header\n0 0 0 1\n1 0 nan 2\n0 1 0.5 3\n3 0 1 2\n";
        let c = parse_ply(p("a.ply"), text.as_bytes()).unwrap();
        assert_eq!(c.points, vec![Point3::origin(), Point3::new(0.0, 1.0, 0.5)]);
        assert_eq!(c.dropped_non_finite, 1);
        // Binary: a leading element with a list property before the vertices.
        let mut b = b"ply\nformat binary_little_endian 1.0\nelement camera 1\nproperty list uchar float k\n\
element vertex 2\nproperty double x\nproperty double y\nproperty double z\nproperty int id\nend_header\n"
            .to_vec();
        b.push(2);
        b.extend(1.0f32.to_le_bytes());
        b.extend(2.0f32.to_le_bytes());
        for (x, y, z, id) in [(0.1, 0.2, 0.3, 1i32), (-1.0, -2.0, -3.0, 2)] {
            b.extend(f64::to_le_bytes(x));
            b.extend(f64::to_le_bytes(y));
            b.extend(f64::to_le_bytes(z));
            b.extend(id.to_le_bytes());
        }
        let c = parse_ply(p("b.ply"), &b).unwrap();
        assert_eq!(
            c.points,
            vec![Point3::new(0.1, 0.2, 0.3), Point3::new(-1.0, -2.0, -3.0)]
        );
        let e = parse_ply(p("b.ply"), &b[..b.len() - 1])
            .unwrap_err()
            .to_string();
        assert!(e.contains("truncated"), "{e}");
    }

    #[test]
    fn ply_errors() {
        let head = |props: &str, n: usize| {
            format!("ply\nformat ascii 1.0\nelement vertex {n}\n{props}end_header\n")
        };
        let xyz = "property float x\nproperty float y\nproperty float z\n";
        let cases = [
            (
                format!("{}0 0\n", head("property float x\nproperty float y\n", 1)),
                "no property 'z'",
            ),
            (format!("{}0 0 0\n", head(xyz, 2)), "truncated"),
            (
                format!("{}0 0\n", head(xyz, 1)),
                "line 8: vertex 0: expected 3 values, found 2",
            ),
            (
                format!("{}0 0 q\n", head(xyz, 1)),
                "line 8: vertex 0, property z: 'q'",
            ),
            (
                format!(
                    "{}0 0 0\n",
                    head("property int x\nproperty float y\nproperty float z\n", 1)
                ),
                "must be float or double",
            ),
            (
                "ply\nformat binary_big_endian 1.0\nend_header\n".to_string(),
                "line 2: unsupported PLY format",
            ),
            (
                "ply\nformat ascii 1.0\nelement vertex 1\n".to_string(),
                "no end_header",
            ),
            (
                "ply\nformat ascii 1.0\nelement face 1\nend_header\n".to_string(),
                "no 'element vertex'",
            ),
            (head(xyz, 0), "is empty"),
        ];
        for (text, want) in cases {
            let e = parse_ply(p("bad.ply"), text.as_bytes())
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("bad.ply") && e.contains(want),
                "want '{want}', got: {e}"
            );
        }
    }
}
