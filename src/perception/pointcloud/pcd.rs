//! The PCD reader: [`parse_pcd`], the header's fields, the record layout they describe,
//! and the ASCII and binary data sections.

use super::{check_count_fits, finish, fmt_err, split_header, CloudError, PointCloud, Scalar};
use std::path::Path;

/// Parses PCD `bytes` read from `path` (used in error messages).
pub fn parse_pcd(path: &Path, bytes: &[u8]) -> Result<PointCloud, CloudError> {
    let (header, data_start) = split_header(path, bytes, |l| l.starts_with("DATA"), "DATA")?;
    let h = pcd_header(path, &header)?;
    let data_kind = h.data_kind;
    let layout = pcd_layout(path, h)?;
    let data = &bytes[data_start..];
    let data_line0 = header.last().map(|h| h.0).unwrap_or(0);
    let raw = match data_kind {
        "ascii" => pcd_ascii(path, &layout, data, data_line0)?,
        "binary" => pcd_binary(path, &layout, data)?,
        "binary_compressed" => {
            return Err(fmt_err(
                path,
                Some(data_line0),
                "DATA binary_compressed is not supported: save as ascii or binary",
            ))
        }
        other => {
            return Err(fmt_err(
                path,
                Some(data_line0),
                format!("unknown DATA kind '{other}' (expected ascii or binary)"),
            ))
        }
    };
    finish(path, raw)
}

/// A PCD header's fields as read, each with its line where a later check names it.
#[derive(Default)]
struct PcdHeader<'a> {
    fields: Option<(usize, Vec<String>)>,
    sizes: Option<(usize, Vec<usize>)>,
    types: Option<(usize, Vec<String>)>,
    counts: Option<(usize, Vec<usize>)>,
    width: Option<usize>,
    height: Option<usize>,
    npoints: Option<(usize, usize)>,
    data_kind: &'a str,
}

/// Reads the header lines `(line number, text)` of a PCD file.
fn pcd_header<'a>(path: &Path, header: &[(usize, &'a str)]) -> Result<PcdHeader<'a>, CloudError> {
    let mut h = PcdHeader::default();
    for &(no, line) in header {
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let mut it = line.split_whitespace();
        let key = it.next().unwrap_or("");
        let rest: Vec<&str> = it.collect();
        let num = |v: &str, what: &str| -> Result<usize, CloudError> {
            v.parse::<usize>()
                .map_err(|_| fmt_err(path, Some(no), format!("{what}: '{v}' is not a count")))
        };
        match key {
            "VERSION" | "VIEWPOINT" => {}
            "FIELDS" => h.fields = Some((no, rest.iter().map(|s| s.to_string()).collect())),
            "SIZE" => {
                let v = rest
                    .iter()
                    .map(|s| num(s, "SIZE"))
                    .collect::<Result<_, _>>()?;
                h.sizes = Some((no, v));
            }
            "TYPE" => h.types = Some((no, rest.iter().map(|s| s.to_string()).collect())),
            "COUNT" => {
                let v = rest
                    .iter()
                    .map(|s| num(s, "COUNT"))
                    .collect::<Result<_, _>>()?;
                h.counts = Some((no, v));
            }
            "WIDTH" | "HEIGHT" | "POINTS" => {
                let [v] = rest.as_slice() else {
                    return Err(fmt_err(path, Some(no), format!("{key} needs one value")));
                };
                let v = num(v, key)?;
                match key {
                    "WIDTH" => h.width = Some(v),
                    "HEIGHT" => h.height = Some(v),
                    _ => h.npoints = Some((no, v)),
                }
            }
            "DATA" => h.data_kind = rest.first().copied().unwrap_or(""),
            other => {
                return Err(fmt_err(
                    path,
                    Some(no),
                    format!("unknown PCD header field '{other}'"),
                ))
            }
        }
    }
    Ok(h)
}

/// Where each point's x, y and z lie in a PCD record, checked against the header.
struct PcdLayout {
    fields: Vec<String>,
    scalars: Vec<Scalar>,
    counts: Vec<usize>,
    /// The fields holding x, y and z.
    xyz: [usize; 3],
    /// POINTS, and its header line.
    n: usize,
    points_line: usize,
}

/// Checks a PCD header's fields against each other (every error names its line).
fn pcd_layout(path: &Path, h: PcdHeader) -> Result<PcdLayout, CloudError> {
    let PcdHeader {
        fields,
        sizes,
        types,
        counts,
        width,
        height,
        npoints,
        ..
    } = h;
    let missing = |f: &str| fmt_err(path, None, format!("header field {f} is missing"));
    let (fl, fields) = fields.ok_or_else(|| missing("FIELDS"))?;
    let (sl, sizes) = sizes.ok_or_else(|| missing("SIZE"))?;
    let (tl, types) = types.ok_or_else(|| missing("TYPE"))?;
    let counts = match counts {
        Some((cl, c)) => {
            if c.len() != fields.len() {
                return Err(fmt_err(
                    path,
                    Some(cl),
                    format!(
                        "COUNT has {} entries but FIELDS has {}",
                        c.len(),
                        fields.len()
                    ),
                ));
            }
            c
        }
        None => vec![1; fields.len()],
    };
    if sizes.len() != fields.len() {
        return Err(fmt_err(
            path,
            Some(sl),
            format!(
                "SIZE has {} entries but FIELDS has {}",
                sizes.len(),
                fields.len()
            ),
        ));
    }
    if types.len() != fields.len() {
        return Err(fmt_err(
            path,
            Some(tl),
            format!(
                "TYPE has {} entries but FIELDS has {}",
                types.len(),
                fields.len()
            ),
        ));
    }
    let mut scalars = Vec::with_capacity(fields.len());
    for k in 0..fields.len() {
        let s = Scalar::pcd(&types[k], sizes[k]).ok_or_else(|| {
            fmt_err(
                path,
                Some(tl),
                format!(
                    "field {}: unsupported TYPE {} with SIZE {}",
                    fields[k], types[k], sizes[k]
                ),
            )
        })?;
        scalars.push(s);
    }
    let mut xyz = [0usize; 3];
    for (a, name) in ["x", "y", "z"].iter().enumerate() {
        let k = fields
            .iter()
            .position(|f| f == name)
            .ok_or_else(|| fmt_err(path, Some(fl), format!("FIELDS has no '{name}' field")))?;
        if !scalars[k].is_float() || counts[k] != 1 {
            return Err(fmt_err(
                path,
                Some(tl),
                format!("field '{name}' must be a single F (float) value"),
            ));
        }
        xyz[a] = k;
    }
    let (pl, n) = npoints.ok_or_else(|| missing("POINTS"))?;
    if let (Some(w), Some(h)) = (width, height) {
        if w.checked_mul(h) != Some(n) {
            return Err(fmt_err(
                path,
                Some(pl),
                format!("POINTS {n} does not equal WIDTH {w} x HEIGHT {h}"),
            ));
        }
    }
    Ok(PcdLayout {
        fields,
        scalars,
        counts,
        xyz,
        n,
        points_line: pl,
    })
}

/// The x, y, z of every point of a PCD file's ASCII data (its first line follows header
/// line `data_line0`).
fn pcd_ascii(
    path: &Path,
    layout: &PcdLayout,
    data: &[u8],
    data_line0: usize,
) -> Result<Vec<[f64; 3]>, CloudError> {
    let PcdLayout {
        fields,
        counts,
        xyz,
        n,
        points_line: pl,
        ..
    } = layout;
    let (n, pl) = (*n, *pl);
    // Column of each field's first value in a text line.
    let mut col = Vec::with_capacity(fields.len());
    let mut c = 0;
    for &cnt in counts {
        col.push(c);
        c += cnt;
    }
    let ncols = c;
    // Each point takes a line: at least one character and its newline (a loose
    // bound, so that a short line still gets its own error below).
    check_count_fits(path, Some(pl), "POINTS", n, 2, data.len())?;
    let text = std::str::from_utf8(data)
        .map_err(|_| fmt_err(path, None, "ASCII data is not UTF-8 text"))?;
    let mut raw = Vec::with_capacity(n);
    for (i, line) in text.lines().enumerate() {
        let no = data_line0 + i + 1;
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        if raw.len() == n {
            return Err(fmt_err(
                path,
                Some(no),
                format!("more than POINTS {n} points"),
            ));
        }
        let vals: Vec<&str> = line.split_whitespace().collect();
        if vals.len() != ncols {
            return Err(fmt_err(
                path,
                Some(no),
                format!("expected {ncols} values, found {}", vals.len()),
            ));
        }
        let mut p = [0.0; 3];
        for a in 0..3 {
            let v = vals[col[xyz[a]]];
            p[a] = v.parse::<f64>().map_err(|_| {
                fmt_err(
                    path,
                    Some(no),
                    format!("field {}: '{v}' is not a number", fields[xyz[a]]),
                )
            })?;
        }
        raw.push(p);
    }
    if raw.len() != n {
        return Err(fmt_err(
            path,
            None,
            format!("header says POINTS {n} but the data has {}", raw.len()),
        ));
    }
    Ok(raw)
}

/// The x, y, z of every point of a PCD file's binary data.
fn pcd_binary(path: &Path, layout: &PcdLayout, data: &[u8]) -> Result<Vec<[f64; 3]>, CloudError> {
    let PcdLayout {
        fields,
        scalars,
        counts,
        xyz,
        n,
        ..
    } = layout;
    let n = *n;
    let mut offs = Vec::with_capacity(fields.len());
    let mut o = 0;
    for k in 0..fields.len() {
        offs.push(o);
        o += scalars[k].size() * counts[k];
    }
    let rec = o;
    let need = rec.saturating_mul(n);
    if data.len() < need {
        return Err(fmt_err(
            path,
            None,
            format!(
                "binary data has {} bytes, POINTS {n} x {rec} bytes needs {need}",
                data.len()
            ),
        ));
    }
    Ok((0..n)
        .map(|i| {
            let r = &data[i * rec..(i + 1) * rec];
            std::array::from_fn(|a| scalars[xyz[a]].read_le(&r[offs[xyz[a]]..]))
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::super::tests::p;
    use super::*;
    use nalgebra::Point3;

    #[test]
    fn pcd_ascii_with_extra_fields_and_nan() {
        let text =
            "# c\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\n\
                    WIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n\
                    1 2 3 255\nnan nan nan 0\n-1.5 0 2e-3 7\n";
        let c = parse_pcd(p("a.pcd"), text.as_bytes()).unwrap();
        assert_eq!(
            c.points,
            vec![Point3::new(1.0, 2.0, 3.0), Point3::new(-1.5, 0.0, 0.002)]
        );
        assert_eq!(c.dropped_non_finite, 1);
    }

    #[test]
    fn pcd_binary_with_mixed_types() {
        let mut b = b"VERSION 0.7\nFIELDS intensity x y z\nSIZE 2 4 8 4\nTYPE U F F F\nCOUNT 1 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA binary\n".to_vec();
        for (i, x, y, z) in [(7u16, 1.0f32, 2.0f64, 3.0f32), (9, -4.0, 5.5, -6.0)] {
            b.extend(i.to_le_bytes());
            b.extend(x.to_le_bytes());
            b.extend(y.to_le_bytes());
            b.extend(z.to_le_bytes());
        }
        let c = parse_pcd(p("b.pcd"), &b).unwrap();
        assert_eq!(
            c.points,
            vec![Point3::new(1.0, 2.0, 3.0), Point3::new(-4.0, 5.5, -6.0)]
        );
        // Truncated binary data names the byte counts.
        let e = parse_pcd(p("b.pcd"), &b[..b.len() - 3])
            .unwrap_err()
            .to_string();
        assert!(e.contains("b.pcd") && e.contains("needs 36"), "{e}");
    }

    #[test]
    fn pcd_errors_name_the_line_or_field() {
        let base = |fields: &str, data: &str| {
            format!("VERSION 0.7\n{fields}\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n{data}")
        };
        let cases = [
            (
                base("FIELDS x y\nSIZE 4 4\nTYPE F F", "1 2\n3 4\n"),
                "no 'z' field",
            ),
            (
                base("FIELDS x y z\nSIZE 4 4\nTYPE F F F", "1 2 3\n"),
                "line 3: SIZE has 2 entries",
            ),
            (
                base("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F", "1 2 3\n4 5\n"),
                "line 10: expected 3 values, found 2",
            ),
            (
                base("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F", "1 2 3\n"),
                "POINTS 2 but the data has 1",
            ),
            (
                base("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F", "1 2 3\n4 5 abc\n"),
                "line 10: field z: 'abc'",
            ),
            (
                base("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F", "nan 1 1\n1 inf 1\n"),
                "empty (2 non-finite",
            ),
            (
                "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 0\n".to_string(),
                "no DATA line",
            ),
            (base("FIELDS x y z\nTYPE F F F", ""), "SIZE is missing"),
            (
                "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 5\nHEIGHT 1\nPOINTS 2\nDATA ascii\n"
                    .to_string(),
                "POINTS 2 does not equal WIDTH 5",
            ),
            (
                "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\nDATA binary_compressed\n"
                    .to_string(),
                "binary_compressed is not supported",
            ),
        ];
        for (text, want) in cases {
            let e = parse_pcd(p("bad.pcd"), text.as_bytes())
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("bad.pcd") && e.contains(want),
                "want '{want}', got: {e}"
            );
        }
    }
}
