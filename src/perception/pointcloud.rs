//! Point clouds for the initial grasp (Sec. V-B): PCD and PLY readers and a PCD writer.
//! The grasp candidates on a cloud (normals, antipodal pairs, the narrow-axis fallback)
//! are in [`super::antipodal`], re-exported here.
//!
//! Supported files:
//! - PCD v0.7 with `DATA ascii` or `DATA binary` (not `binary_compressed`); fields
//!   `x y z` of type `F` (size 4 or 8); any other fields are skipped.
//! - PLY with `format ascii 1.0` or `format binary_little_endian 1.0`; the `vertex`
//!   element must have `x y z` of type float/float32 or double/float64; other properties
//!   and elements (faces, list properties) are skipped.
//!
//! Points with a NaN or infinite coordinate are dropped and counted
//! ([`PointCloud::dropped_non_finite`]); a cloud with no finite point is an error.

use nalgebra::Point3;
use std::path::{Path, PathBuf};

/// Error while reading or writing a point cloud.
#[derive(Debug, thiserror::Error)]
pub enum CloudError {
    /// The file cannot be read.
    #[error("cannot read point cloud {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The file is malformed; `line` is the 1-based header or ASCII data line when known.
    #[error("invalid point cloud {path}{}: {detail}", line.map(|l| format!(", line {l}")).unwrap_or_default())]
    Format {
        /// The file.
        path: PathBuf,
        /// 1-based line, if the problem is on one line.
        line: Option<usize>,
        /// What is wrong (names the header field or value).
        detail: String,
    },
    /// The cloud has no finite point.
    #[error("point cloud {path} is empty ({dropped} non-finite points dropped)")]
    Empty {
        /// The file.
        path: PathBuf,
        /// Non-finite points that were dropped.
        dropped: usize,
    },
    /// The cloud cannot be written.
    #[error(transparent)]
    Write(#[from] crate::util::fsx::WriteError),
    /// The cloud has fewer points than a surface normal is fitted to.
    #[error(
        "the point cloud has only {points} points: at least {needed} are needed (each \
         surface normal is fitted to a point's {needed} nearest neighbours)"
    )]
    TooFewPoints {
        /// Points in the cloud.
        points: usize,
        /// Points needed.
        needed: usize,
    },
    /// A parameter of a cloud operation is out of range.
    #[error("invalid parameter {name}: {detail}")]
    BadParameter {
        /// The parameter.
        name: &'static str,
        /// What is wrong.
        detail: String,
    },
}

/// A point cloud read from a file.
#[derive(Debug, Clone, PartialEq)]
pub struct PointCloud {
    /// The finite points (m).
    pub points: Vec<Point3<f64>>,
    /// How many points with NaN or infinite coordinates were dropped.
    pub dropped_non_finite: usize,
}

impl PointCloud {
    /// Reads a `.pcd` or `.ply` file (chosen by extension, else by the first bytes).
    pub fn load(path: &Path) -> Result<Self, CloudError> {
        let bytes = std::fs::read(path).map_err(|source| CloudError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        match ext.as_deref() {
            Some("pcd") => parse_pcd(path, &bytes),
            Some("ply") => parse_ply(path, &bytes),
            _ if bytes.starts_with(b"ply") => parse_ply(path, &bytes),
            _ => parse_pcd(path, &bytes),
        }
    }

    /// The centroid of the points.
    pub fn centroid(&self) -> Point3<f64> {
        centroid(&self.points)
    }
}

/// Layout of a PCD file's DATA section.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PcdData {
    /// One point per text line.
    Ascii,
    /// Packed little-endian records.
    Binary,
}

/// Writes `points` as a PCD v0.7 file with fields `x y z` (f32 for binary, full
/// precision text for ASCII), atomically. Non-finite points are written as `nan`.
pub fn write_pcd(path: &Path, points: &[Point3<f64>], data: PcdData) -> Result<(), CloudError> {
    let n = points.len();
    let (size, ty, tag) = match data {
        PcdData::Ascii => ("8 8 8", "F F F", "ascii"),
        PcdData::Binary => ("4 4 4", "F F F", "binary"),
    };
    let mut out = format!(
        "# .PCD v0.7 - written by grasp\nVERSION 0.7\nFIELDS x y z\nSIZE {size}\nTYPE {ty}\n\
         COUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA {tag}\n"
    )
    .into_bytes();
    match data {
        PcdData::Ascii => {
            for p in points {
                out.extend_from_slice(format!("{} {} {}\n", p.x, p.y, p.z).as_bytes());
            }
        }
        PcdData::Binary => {
            for p in points {
                for c in [p.x, p.y, p.z] {
                    out.extend_from_slice(&(c as f32).to_le_bytes());
                }
            }
        }
    }
    crate::util::fsx::write_atomic(path, &out)?;
    Ok(())
}

/// Refuses a header's count that the data cannot hold: `count` items of at least
/// `min_bytes` bytes each (a text line's values with their separators, a binary record)
/// in `data_len` bytes. Checked before anything is allocated, so a count such as
/// `element vertex 4000000000` in a small file is an error, not an aborted allocation.
fn check_count_fits(
    path: &Path,
    line: Option<usize>,
    what: &str,
    count: usize,
    min_bytes: usize,
    data_len: usize,
) -> Result<(), CloudError> {
    // A text file's last line may lack its newline: one byte less.
    if count.saturating_mul(min_bytes).saturating_sub(1) > data_len {
        return Err(fmt_err(
            path,
            line,
            format!(
                "{what} {count} cannot fit in the {data_len} bytes of data (each takes at \
                 least {min_bytes} bytes): the count is wrong or the file is truncated"
            ),
        ));
    }
    Ok(())
}

fn fmt_err(path: &Path, line: Option<usize>, detail: impl Into<String>) -> CloudError {
    CloudError::Format {
        path: path.to_path_buf(),
        line,
        detail: detail.into(),
    }
}

/// Header lines with their 1-based line numbers.
type HeaderLines<'a> = Vec<(usize, &'a str)>;

/// Splits the header of a text-headed file: returns (header lines with their 1-based
/// numbers, byte offset of the data). `is_last` says which line ends the header.
fn split_header<'a>(
    path: &Path,
    bytes: &'a [u8],
    is_last: impl Fn(&str) -> bool,
    what: &str,
) -> Result<(HeaderLines<'a>, usize), CloudError> {
    let mut lines = Vec::new();
    let mut pos = 0;
    let mut no = 0;
    while pos < bytes.len() {
        let end = bytes[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .map(|e| pos + e + 1)
            .unwrap_or(bytes.len());
        no += 1;
        let raw = &bytes[pos..end];
        let text = std::str::from_utf8(raw)
            .map_err(|_| fmt_err(path, Some(no), "header line is not UTF-8 text"))?
            .trim();
        pos = end;
        lines.push((no, text));
        if is_last(text) {
            return Ok((lines, pos));
        }
    }
    Err(fmt_err(path, None, format!("header has no {what} line")))
}

/// One scalar type of a PCD field or PLY property.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
}

impl Scalar {
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::I64 | Scalar::U64 | Scalar::F64 => 8,
        }
    }

    fn is_float(self) -> bool {
        matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// Reads a little-endian value; `b` has at least `size()` bytes.
    fn read_le(self, b: &[u8]) -> f64 {
        let a = |n: usize| -> [u8; 8] {
            let mut x = [0u8; 8];
            x[..n].copy_from_slice(&b[..n]);
            x
        };
        match self {
            Scalar::I8 => f64::from(b[0] as i8),
            Scalar::U8 => f64::from(b[0]),
            Scalar::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
            Scalar::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
            Scalar::I32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::I64 => i64::from_le_bytes(a(8)) as f64,
            Scalar::U64 => u64::from_le_bytes(a(8)) as f64,
            Scalar::F64 => f64::from_le_bytes(a(8)),
        }
    }

    fn pcd(ty: &str, size: usize) -> Option<Scalar> {
        Some(match (ty, size) {
            ("I", 1) => Scalar::I8,
            ("U", 1) => Scalar::U8,
            ("I", 2) => Scalar::I16,
            ("U", 2) => Scalar::U16,
            ("I", 4) => Scalar::I32,
            ("U", 4) => Scalar::U32,
            ("I", 8) => Scalar::I64,
            ("U", 8) => Scalar::U64,
            ("F", 4) => Scalar::F32,
            ("F", 8) => Scalar::F64,
            _ => return None,
        })
    }

    fn ply(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }
}

fn finish(path: &Path, raw: Vec<[f64; 3]>) -> Result<PointCloud, CloudError> {
    let total = raw.len();
    let points: Vec<Point3<f64>> = raw
        .into_iter()
        .filter(|p| p.iter().all(|c| c.is_finite()))
        .map(|p| Point3::new(p[0], p[1], p[2]))
        .collect();
    let dropped = total - points.len();
    if points.is_empty() {
        return Err(CloudError::Empty {
            path: path.to_path_buf(),
            dropped,
        });
    }
    Ok(PointCloud {
        points,
        dropped_non_finite: dropped,
    })
}

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

pub use super::antipodal::{
    antipodal_grasps, centroid, estimate_normals, grasp_candidates, principal_axis_grasp,
    AntipodalConfig, GraspCandidate,
};

#[cfg(test)]
mod tests {
    use super::*;

    fn p(path: &str) -> &Path {
        Path::new(path)
    }

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

    #[test]
    fn counts_beyond_the_file_are_refused_before_allocating() {
        // Before the check, each of these asked for 96 GB ("memory allocation failed",
        // SIGABRT) instead of returning an error.
        let n = 4_000_000_000usize;
        let xyz = "property float x\nproperty float y\nproperty float z\n";
        let ply_ascii =
            format!("ply\nformat ascii 1.0\nelement vertex {n}\n{xyz}end_header\n0 0 0\n");
        let mut ply_bin =
            format!("ply\nformat binary_little_endian 1.0\nelement vertex {n}\n{xyz}end_header\n")
                .into_bytes();
        ply_bin.extend_from_slice(&[0u8; 12]);
        let pcd_ascii = format!(
            "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nPOINTS {n}\nDATA ascii\n0 0 0\n"
        );
        let cases: [(&str, Vec<u8>, &str); 3] = [
            (
                "big.ply",
                ply_ascii.into_bytes(),
                "line 3: element vertex 4000000000 cannot fit in the 6 bytes",
            ),
            (
                "big.ply",
                ply_bin,
                "line 3: element vertex 4000000000 cannot fit in the 12 bytes",
            ),
            (
                "big.pcd",
                pcd_ascii.into_bytes(),
                "line 6: POINTS 4000000000 cannot fit in the 6 bytes",
            ),
        ];
        for (name, bytes, want) in cases {
            let e = if name.ends_with("ply") {
                parse_ply(p(name), &bytes)
            } else {
                parse_pcd(p(name), &bytes)
            }
            .unwrap_err()
            .to_string();
            assert!(
                e.contains(name) && e.contains(want),
                "want '{want}', got: {e}"
            );
        }
        // A count the data can hold still reads (the last line without its newline).
        let ok = format!("ply\nformat ascii 1.0\nelement vertex 2\n{xyz}end_header\n0 0 0\n1 1 1");
        assert_eq!(
            parse_ply(p("ok.ply"), ok.as_bytes()).unwrap().points.len(),
            2
        );
    }

    #[test]
    fn pcd_write_read_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let pts = vec![Point3::new(0.5, -0.25, 0.125), Point3::new(1.0, 2.0, 3.0)];
        for kind in [PcdData::Ascii, PcdData::Binary] {
            let f = dir.path().join(format!("{kind:?}.pcd"));
            write_pcd(&f, &pts, kind).unwrap();
            assert_eq!(PointCloud::load(&f).unwrap().points, pts);
        }
        let e = PointCloud::load(&dir.path().join("none.pcd"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("none.pcd"));
    }
}
