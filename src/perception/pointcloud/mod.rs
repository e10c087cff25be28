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
//!
//! The two readers are submodules, re-exported here: `pcd` holds the PCD reader, `ply`
//! the PLY reader. This file holds the cloud and its loader, its errors, the PCD writer,
//! and what both readers share: the header splitting, the scalar types, the check that a
//! header's count fits the data.

use nalgebra::Point3;
use std::path::{Path, PathBuf};

mod pcd;
mod ply;

pub use pcd::parse_pcd;
pub use ply::parse_ply;

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
        let bytes = crate::util::fsx::read_bounded(path, crate::util::fsx::limits::MESH).map_err(
            |source| CloudError::Io {
                path: path.to_path_buf(),
                source,
            },
        )?;
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

pub use super::antipodal::{
    antipodal_grasps, centroid, estimate_normals, grasp_candidates, principal_axis_grasp,
    AntipodalConfig, GraspCandidate,
};

#[cfg(test)]
mod tests {
    use super::*;

    pub(super) fn p(path: &str) -> &Path {
        Path::new(path)
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
