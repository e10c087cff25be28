//! Tactile calibration of the real hand, exactly as in Sec. V-C of the paper.
//!
//! - The **lower** range of each fingertip sensor is the mean of 10 raw readings taken
//!   with the hand still and nothing touching it.
//! - The **upper** range of each fingertip is the maximum raw reading recorded while an
//!   operator presses that fingertip.
//! - A reading is a contact (observation 1) when
//!   `raw > lower + fraction * (upper - lower)`, with `fraction = 0.003` (0.3 % of the range).
//!
//! The calibration is stored as a small JSON file:
//! `{"lower": [5 numbers], "upper": [5 numbers], "threshold_fraction": 0.003}`.

use crate::robot::joints::FINGERS;
use crate::robot::joints::N_TACTILE;
use std::path::{Path, PathBuf};

/// The paper's contact threshold: 0.3 % of the sensor range.
pub const DEFAULT_THRESHOLD_FRACTION: f64 = 0.003;
/// Number of still readings the lower range is averaged over (Sec. V-C: ten).
pub const MIN_STILL_READINGS: usize = 10;

/// Error of the tactile calibration.
#[derive(Debug, thiserror::Error)]
pub enum CalibrationError {
    /// Fewer still readings than required.
    #[error("tactile calibration needs at least {needed} still readings, got {got}")]
    TooFewReadings {
        /// Required number.
        needed: usize,
        /// Number received.
        got: usize,
    },
    /// A fingertip was never pressed during the upper-range procedure.
    #[error("fingertip {finger} was never pressed: no upper range recorded")]
    NotPressed {
        /// Finger name (FF, MF, RF, LF, TH).
        finger: &'static str,
    },
    /// A value is NaN or infinite.
    #[error("{field}: value {value} is not finite")]
    NonFinite {
        /// The field, e.g. `lower[2] (RF)`.
        field: String,
        /// The value.
        value: f64,
    },
    /// A value beyond any sensor's raw range ([`MAX_RAW`]).
    #[error(
        "{field}: value {} is beyond any fingertip sensor's raw reading (at most {MAX_RAW} in \
         magnitude); with it no contact would ever be detected",
        crate::util::num::short(*value)
    )]
    OutOfRange {
        /// The field, e.g. `upper[2] (RF)`.
        field: String,
        /// The value.
        value: f64,
    },
    /// The upper range is not above the lower range.
    #[error("fingertip {finger}: upper range {upper} must be greater than lower range {lower}")]
    EmptyRange {
        /// Finger name.
        finger: &'static str,
        /// Lower range.
        lower: f64,
        /// Upper range.
        upper: f64,
    },
    /// The threshold fraction is not in (0, 1).
    #[error("threshold_fraction {0} must be in (0, 1)")]
    BadFraction(f64),
    /// A finger index out of 0..5.
    #[error("finger index {0} out of range 0..5")]
    BadFinger(usize),
    /// The calibration file cannot be read.
    #[error("cannot read calibration file {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The calibration file is malformed; the message names the field.
    #[error("invalid calibration file {path}: {detail}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// What is wrong (field, line and column).
        detail: String,
    },
    /// The calibration file cannot be written.
    #[error(transparent)]
    Write(#[from] crate::util::fsx::WriteError),
}

/// The largest magnitude of a raw fingertip reading a calibration may hold: far above the
/// sensors' range (the simulated ones read a few hundred to a few thousand, 16-bit ADCs
/// at most 65,535).
pub const MAX_RAW: f64 = 1e6;

/// A tactile calibration: per-fingertip lower and upper ranges and the contact threshold.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TactileCalibration {
    /// Lower range per fingertip (FF, MF, RF, LF, TH): mean still reading.
    pub lower: [f64; N_TACTILE],
    /// Upper range per fingertip: maximum reading while pressed.
    pub upper: [f64; N_TACTILE],
    /// Fraction of the range above `lower` that counts as contact (paper: 0.003).
    pub threshold_fraction: f64,
}

impl TactileCalibration {
    /// A calibration from explicit ranges, validated (finite, `upper > lower`,
    /// fraction in (0, 1)).
    pub fn new(
        lower: [f64; N_TACTILE],
        upper: [f64; N_TACTILE],
        threshold_fraction: f64,
    ) -> Result<Self, CalibrationError> {
        let c = TactileCalibration {
            lower,
            upper,
            threshold_fraction,
        };
        c.validate()?;
        Ok(c)
    }

    /// Checks every invariant of the calibration.
    pub fn validate(&self) -> Result<(), CalibrationError> {
        for (k, &finger) in FINGERS.iter().enumerate() {
            for (name, v) in [("lower", self.lower[k]), ("upper", self.upper[k])] {
                if !v.is_finite() {
                    return Err(CalibrationError::NonFinite {
                        field: format!("{name}[{k}] ({finger})"),
                        value: v,
                    });
                }
                if v.abs() > MAX_RAW {
                    return Err(CalibrationError::OutOfRange {
                        field: format!("{name}[{k}] ({finger})"),
                        value: v,
                    });
                }
            }
            if self.upper[k] <= self.lower[k] {
                return Err(CalibrationError::EmptyRange {
                    finger,
                    lower: self.lower[k],
                    upper: self.upper[k],
                });
            }
        }
        let f = self.threshold_fraction;
        if !(f.is_finite() && f > 0.0 && f < 1.0) {
            return Err(CalibrationError::BadFraction(f));
        }
        Ok(())
    }

    /// The raw value above which fingertip `k` is in contact:
    /// `lower[k] + fraction * (upper[k] - lower[k])`.
    pub fn threshold(&self, k: usize) -> f64 {
        self.lower[k] + self.threshold_fraction * (self.upper[k] - self.lower[k])
    }

    /// The binary tactile observation: `raw[k] > threshold(k)`. A NaN reading is never a
    /// contact (validate readings with [`RawSensors::validate`](super::RawSensors::validate)).
    pub fn contacts(&self, raw: &[f64; N_TACTILE]) -> [bool; N_TACTILE] {
        std::array::from_fn(|k| raw[k] > self.threshold(k))
    }

    /// Saves the calibration as pretty JSON, atomically.
    pub fn save(&self, path: &Path) -> Result<(), CalibrationError> {
        self.validate()?;
        let text = serde_json::to_string_pretty(self).map_err(|e| CalibrationError::Parse {
            path: path.to_path_buf(),
            detail: format!("cannot serialise the calibration: {e}"),
        })?;
        crate::util::fsx::write_atomic(path, text.as_bytes())?;
        Ok(())
    }

    /// Loads and validates a calibration file; errors name the file and the field.
    pub fn load(path: &Path) -> Result<Self, CalibrationError> {
        let text = crate::util::fsx::read_to_string_bounded(path, crate::util::fsx::limits::CONFIG)
            .map_err(|source| CalibrationError::Read {
                path: path.to_path_buf(),
                source,
            })?;
        Self::parse(path, &text)
    }

    /// Parses calibration JSON `text` read from `path` (used in error messages).
    pub fn parse(path: &Path, text: &str) -> Result<Self, CalibrationError> {
        let parse_err = |detail: String| CalibrationError::Parse {
            path: path.to_path_buf(),
            detail,
        };
        // JSON has no NaN; serde_json reports `null` or a wrong length with line/column.
        let c: TactileCalibration =
            serde_json::from_str(text).map_err(|e| parse_err(e.to_string()))?;
        c.validate().map_err(|e| parse_err(e.to_string()))?;
        Ok(c)
    }
}

/// The calibration procedure of Sec. V-C as an accumulator: feed still readings, then
/// the readings recorded while each fingertip is pressed, then [`finish`](Self::finish).
#[derive(Debug, Clone, Default)]
pub struct TactileCalibrator {
    still_sum: [f64; N_TACTILE],
    still_count: usize,
    upper: [Option<f64>; N_TACTILE],
}

impl TactileCalibrator {
    /// An empty calibrator.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds one reading of all five sensors taken with the hand still and untouched.
    pub fn add_still(&mut self, raw: &[f64; N_TACTILE]) -> Result<(), CalibrationError> {
        check_finite("still reading", raw)?;
        for (s, r) in self.still_sum.iter_mut().zip(raw) {
            *s += r;
        }
        self.still_count += 1;
        Ok(())
    }

    /// Adds one reading of all five sensors taken while fingertip `finger` (0..5, FF, MF,
    /// RF, LF, TH) is pressed; only that fingertip's value is used.
    pub fn add_press(
        &mut self,
        finger: usize,
        raw: &[f64; N_TACTILE],
    ) -> Result<(), CalibrationError> {
        if finger >= N_TACTILE {
            return Err(CalibrationError::BadFinger(finger));
        }
        check_finite("press reading", raw)?;
        let v = raw[finger];
        let u = &mut self.upper[finger];
        *u = Some(u.map_or(v, |old| old.max(v)));
        Ok(())
    }

    /// The lower ranges: the mean of the still readings (at least [`MIN_STILL_READINGS`]).
    pub fn lower(&self) -> Result<[f64; N_TACTILE], CalibrationError> {
        if self.still_count < MIN_STILL_READINGS {
            return Err(CalibrationError::TooFewReadings {
                needed: MIN_STILL_READINGS,
                got: self.still_count,
            });
        }
        let n = self.still_count as f64;
        Ok(self.still_sum.map(|s| s / n))
    }

    /// Builds the validated calibration with contact fraction `threshold_fraction`.
    pub fn finish(&self, threshold_fraction: f64) -> Result<TactileCalibration, CalibrationError> {
        let lower = self.lower()?;
        let mut upper = [0.0; N_TACTILE];
        for k in 0..N_TACTILE {
            upper[k] = self.upper[k].ok_or(CalibrationError::NotPressed { finger: FINGERS[k] })?;
        }
        TactileCalibration::new(lower, upper, threshold_fraction)
    }
}

/// Runs the whole procedure from two sources of readings: `still` yields readings with
/// the hand still (all are averaged, at least 10), `presses` yields `(finger, reading)`
/// pairs recorded while that fingertip is pressed.
pub fn calibrate<S, P>(
    still: S,
    presses: P,
    threshold_fraction: f64,
) -> Result<TactileCalibration, CalibrationError>
where
    S: IntoIterator<Item = [f64; N_TACTILE]>,
    P: IntoIterator<Item = (usize, [f64; N_TACTILE])>,
{
    let mut c = TactileCalibrator::new();
    for r in still {
        c.add_still(&r)?;
    }
    for (f, r) in presses {
        c.add_press(f, &r)?;
    }
    c.finish(threshold_fraction)
}

fn check_finite(what: &str, raw: &[f64; N_TACTILE]) -> Result<(), CalibrationError> {
    match raw.iter().position(|v| !v.is_finite()) {
        Some(k) => Err(CalibrationError::NonFinite {
            field: format!("{what} [{k}] ({})", FINGERS[k]),
            value: raw[k],
        }),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn threshold_is_lower_plus_0_3_percent_of_range_hand_computed() {
        // FF: lower 100, upper 1100 -> range 1000 -> threshold 100 + 3 = 103.
        let c = TactileCalibration::new(
            [100.0, 0.0, 50.0, 10.0, -20.0],
            [1100.0, 2000.0, 150.0, 20.0, 180.0],
            DEFAULT_THRESHOLD_FRACTION,
        )
        .unwrap();
        assert!((c.threshold(0) - 103.0).abs() < 1e-12);
        assert!((c.threshold(1) - 6.0).abs() < 1e-12);
        assert!((c.threshold(2) - 50.3).abs() < 1e-12);
        assert!((c.threshold(3) - 10.03).abs() < 1e-12);
        assert!((c.threshold(4) - (-19.4)).abs() < 1e-12);
        // Strictly above the threshold is a contact.
        let t = c.contacts(&[103.0, 6.01, 50.0, 11.0, -19.0]);
        assert_eq!(t, [false, true, false, true, true]);
    }

    #[test]
    fn procedure_mean_of_still_and_max_of_presses() {
        let still: Vec<[f64; 5]> = (0..10)
            .map(|i| {
                let d = if i % 2 == 0 { 1.0 } else { -1.0 };
                [200.0 + d, 300.0, 400.0 - d, 500.0, 600.0]
            })
            .collect();
        let presses = vec![
            (0, [900.0, 0.0, 0.0, 0.0, 0.0]),
            (0, [1200.0, 9999.0, 0.0, 0.0, 0.0]), // other fingers' values ignored
            (0, [1000.0, 0.0, 0.0, 0.0, 0.0]),
            (1, [0.0, 1300.0, 0.0, 0.0, 0.0]),
            (2, [0.0, 0.0, 1400.0, 0.0, 0.0]),
            (3, [0.0, 0.0, 0.0, 1500.0, 0.0]),
            (4, [0.0, 0.0, 0.0, 0.0, 1600.0]),
        ];
        let c = calibrate(still, presses, 0.003).unwrap();
        assert_eq!(c.lower, [200.0, 300.0, 400.0, 500.0, 600.0]);
        assert_eq!(c.upper, [1200.0, 1300.0, 1400.0, 1500.0, 1600.0]);
        // FF: 200 + 0.003 * 1000 = 203.
        assert!((c.threshold(0) - 203.0).abs() < 1e-9);
    }

    #[test]
    fn procedure_errors() {
        let nine = vec![[1.0; 5]; 9];
        let e = calibrate(nine, vec![], 0.003).unwrap_err();
        assert!(matches!(
            e,
            CalibrationError::TooFewReadings { needed: 10, got: 9 }
        ));
        let ten = vec![[1.0; 5]; 10];
        let presses: Vec<_> = (0..4).map(|f| (f, [5.0; 5])).collect();
        let e = calibrate(ten.clone(), presses, 0.003).unwrap_err();
        assert!(e.to_string().contains("TH was never pressed"), "{e}");
        // upper <= lower
        let presses: Vec<_> = (0..5).map(|f| (f, [1.0; 5])).collect();
        let e = calibrate(ten.clone(), presses, 0.003).unwrap_err();
        assert!(
            matches!(e, CalibrationError::EmptyRange { finger: "FF", .. }),
            "{e}"
        );
        let mut bad = ten.clone();
        bad[3][2] = f64::NAN;
        let e = calibrate(bad, vec![], 0.003).unwrap_err();
        assert!(e.to_string().contains("(RF)"), "{e}");
        let mut c = TactileCalibrator::new();
        assert!(matches!(
            c.add_press(5, &[1.0; 5]),
            Err(CalibrationError::BadFinger(5))
        ));
        assert!(matches!(
            TactileCalibration::new([0.0; 5], [1.0; 5], 0.0),
            Err(CalibrationError::BadFraction(_))
        ));
        // Beyond any sensor's raw range: no contact would ever be detected.
        let e = TactileCalibration::new([0.0; 5], [1e300, 1.0, 1.0, 1.0, 1.0], 0.003)
            .unwrap_err()
            .to_string();
        assert!(e.contains("upper[0] (FF)") && e.contains("1e300"), "{e}");
    }

    #[test]
    fn json_round_trip_and_bad_files() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("tactile.json");
        let c = TactileCalibration::new([1.0, 2.0, 3.0, 4.0, 5.0], [10.0; 5], 0.01).unwrap();
        c.save(&p).unwrap();
        assert_eq!(TactileCalibration::load(&p).unwrap(), c);

        let path = Path::new("cal.json");
        let short =
            r#"{"lower": [1,2,3,4], "upper": [10,10,10,10,10], "threshold_fraction": 0.003}"#;
        let e = TactileCalibration::parse(path, short)
            .unwrap_err()
            .to_string();
        assert!(e.contains("cal.json") && e.contains("length"), "{e}");
        let nan =
            r#"{"lower": [1,2,3,4,null], "upper": [10,10,10,10,10], "threshold_fraction": 0.003}"#;
        let e = TactileCalibration::parse(path, nan)
            .unwrap_err()
            .to_string();
        assert!(e.contains("cal.json") && e.contains("line 1"), "{e}");
        let inverted =
            r#"{"lower": [1,2,3,4,50], "upper": [10,10,10,10,10], "threshold_fraction": 0.003}"#;
        let e = TactileCalibration::parse(path, inverted)
            .unwrap_err()
            .to_string();
        assert!(e.contains("TH") && e.contains("upper range 10"), "{e}");
        let unknown = r#"{"lower": [1,2,3,4,5], "upper": [10,10,10,10,10], "threshold_fraction": 0.003, "x": 1}"#;
        let e = TactileCalibration::parse(path, unknown)
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown field"), "{e}");
        let missing = TactileCalibration::load(&dir.path().join("nope.json")).unwrap_err();
        assert!(missing.to_string().contains("nope.json"));
    }
}
