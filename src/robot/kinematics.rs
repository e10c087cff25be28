//! Forward kinematics over a [`Robot`]'s tree, and the hand's named postures.

use super::joints::{finger_index, HAND_JOINTS};
use super::model::Robot;
use nalgebra::{Isometry3, Point3};

impl Robot {
    /// Poses of every link in the root frame for joint positions `q` (one entry per joint,
    /// indexed like [`Robot::joints`]; entries of fixed joints are ignored).
    pub fn fk(&self, q: &[f64]) -> Vec<Isometry3<f64>> {
        let mut poses = vec![Isometry3::identity(); self.links.len()];
        for (k, j) in self.joints.iter().enumerate() {
            let qk = q.get(k).copied().unwrap_or(0.0);
            poses[j.child] = poses[j.parent] * j.origin * j.motion(qk);
        }
        poses
    }

    /// Link poses in the palm frame for the 24 hand joint angles (paper order).
    pub fn hand_fk_palm(&self, hand: &[f64; 24]) -> Vec<Isometry3<f64>> {
        let mut q = self.zero_q();
        self.set_hand_q(&mut q, hand);
        let poses = self.fk(&q);
        let inv = poses[self.hand.palm].inverse();
        poses.into_iter().map(|p| inv * p).collect()
    }

    /// The points M3G's surface vectors start from, in the palm frame: the centre of the
    /// first collision element of each distal phalanx (FF, MF, RF, LF, TH) and of the
    /// palm (the simulator's collider centres for the same joint angles).
    pub fn surface_points_palm(&self, hand: &[f64; 24]) -> [Point3<f64>; 6] {
        let poses = self.hand_fk_palm(hand);
        let links = [
            self.hand.distal[0],
            self.hand.distal[1],
            self.hand.distal[2],
            self.hand.distal[3],
            self.hand.distal[4],
            self.hand.palm,
        ];
        links.map(|l| {
            let origin = self.links[l]
                .collisions
                .first()
                .map_or(Isometry3::identity(), |c| c.origin);
            Point3::from((poses[l] * origin).translation.vector)
        })
    }

    /// The five fingertip positions (FF, MF, RF, LF, TH) in the palm frame.
    pub fn fingertips_palm(&self, hand: &[f64; 24]) -> [Point3<f64>; 5] {
        let poses = self.hand_fk_palm(hand);
        self.hand
            .tips
            .map(|t| Point3::from(poses[t].translation.vector))
    }
}

/// A named hand posture for `grasp robot show --q`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Posture {
    /// All joints at zero: a flat hand.
    Zero,
    /// The open start posture of an episode: fingers straight, thumb abducted under the
    /// palm, ready to close.
    Open,
    /// The "C" shape of the paper's grasp mapping (Sec. V-B): fingers and thumb curved so
    /// the hand forms a C around an object.
    CShape,
}

impl std::str::FromStr for Posture {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "zero" => Ok(Posture::Zero),
            "open" => Ok(Posture::Open),
            "c-shape" | "cshape" | "c" => Ok(Posture::CShape),
            other => Err(format!(
                "unknown posture '{other}': expected zero, open, c-shape or a file"
            )),
        }
    }
}

impl Posture {
    /// The 24 hand joint angles (paper order) of this posture.
    pub fn angles(self) -> [f64; 24] {
        let mut q = [0.0; 24];
        let mut set = |name: &str, v: f64| {
            if let Some(i) = finger_index(name) {
                q[i + 2] = v;
            }
        };
        match self {
            Posture::Zero => {}
            Posture::Open => {
                set("THJ5", 0.0);
                set("THJ4", 1.15);
                set("THJ1", 0.0);
                for f in ["FF", "MF", "RF", "LF"] {
                    set(&format!("{f}J3"), 0.05);
                }
            }
            Posture::CShape => {
                for f in ["FF", "MF", "RF", "LF"] {
                    set(&format!("{f}J3"), 0.35);
                    set(&format!("{f}J2"), 0.35);
                    set(&format!("{f}J1"), 0.35);
                }
                set("LFJ5", 0.2);
                set("THJ5", 0.35);
                set("THJ4", 1.15);
                set("THJ2", 0.2);
                set("THJ1", 0.25);
            }
        }
        q
    }
}

/// Reads a posture file: one `NAME VALUE` or `NAME,VALUE` pair per line (joint names with
/// or without `rh_`/`lh_` prefix, radians; `#` starts a comment). Joints not named are 0.
pub fn parse_posture(text: &str, origin: &str) -> Result<[f64; 24], String> {
    let mut q = [0.0; 24];
    for (n, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let mut parts = line
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|s| !s.is_empty());
        let (Some(name), Some(val), None) = (parts.next(), parts.next(), parts.next()) else {
            return Err(format!(
                "{origin}, line {}: expected 'JOINT VALUE', got '{line}'",
                n + 1
            ));
        };
        let base = super::joints::canonical_name(name);
        let Some(k) = HAND_JOINTS.iter().position(|j| *j == base) else {
            return Err(format!(
                "{origin}, line {}: unknown joint '{name}' (known: {})",
                n + 1,
                HAND_JOINTS.join(", ")
            ));
        };
        let v: f64 = val
            .parse()
            .map_err(|_| format!("{origin}, line {}: '{val}' is not a number", n + 1))?;
        if !v.is_finite() {
            return Err(format!("{origin}, line {}: value is not finite", n + 1));
        }
        q[k] = v;
    }
    Ok(q)
}

/// Checks hand joint angles against the robot's limits; names the first violation.
pub fn check_limits(robot: &Robot, q: &[f64; 24], tol: f64) -> Result<(), String> {
    for (k, (lo, hi)) in robot.hand_limits().iter().enumerate() {
        if q[k] < lo - tol || q[k] > hi + tol {
            return Err(format!(
                "joint {} = {:.4} rad is outside its limits [{lo:.4}, {hi:.4}]",
                HAND_JOINTS[k], q[k]
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::joints::Side;
    use nalgebra::Vector3;

    fn close(a: Point3<f64>, b: [f64; 3], tol: f64) -> bool {
        (a.coords - Vector3::from(b)).norm() < tol
    }

    #[test]
    fn right_hand_zero_posture_tips_hand_computed() {
        let r = Robot::builtin(Side::Right);
        let tips = r.fingertips_palm(&[0.0; 24]);
        // FF: knuckle (0.033, 0, 0.095) + 0.045 + 0.025 + 0.026 along z.
        assert!(close(tips[0], [0.033, 0.0, 0.191], 1e-9), "{}", tips[0]);
        assert!(close(tips[1], [0.011, 0.0, 0.195], 1e-9), "{}", tips[1]);
        assert!(close(tips[2], [-0.011, 0.0, 0.191], 1e-9), "{}", tips[2]);
        // LF: metacarpal (-0.033, 0, 0.02071) + 0.06579 + 0.096.
        assert!(close(tips[3], [-0.033, 0.0, 0.1825], 1e-9), "{}", tips[3]);
        // TH: base (0.034, -0.0085, 0.029) + Ry(pi/4) (0, 0, 0.0975).
        let s = 0.0975 * std::f64::consts::FRAC_1_SQRT_2;
        assert!(
            close(tips[4], [0.034 + s, -0.0085, 0.029 + s], 1e-7),
            "{}",
            tips[4]
        );
        assert!(close(tips[4], [0.1029, -0.0085, 0.0979], 1e-4));
    }

    #[test]
    fn left_hand_is_the_mirror_for_any_posture() {
        let r = Robot::builtin(Side::Right);
        let l = Robot::builtin(Side::Left);
        for q in [
            [0.0; 24],
            Posture::CShape.angles(),
            std::array::from_fn(|k| {
                let (lo, hi) = r.hand_limits()[k];
                lo + (hi - lo) * (0.2 + 0.6 * ((k * 7 % 11) as f64 / 11.0))
            }),
        ] {
            let tr = r.fingertips_palm(&q);
            let tl = l.fingertips_palm(&q);
            for f in 0..5 {
                let m = Point3::new(-tr[f].x, tr[f].y, tr[f].z);
                assert!((m - tl[f]).norm() < 1e-9, "finger {f}: {} vs {}", m, tl[f]);
            }
        }
    }

    #[test]
    fn flexing_j3_moves_the_tip_toward_the_palm_side() {
        // The palm faces -y: flexion must move fingertips to -y.
        for side in [Side::Left, Side::Right] {
            let r = Robot::builtin(side);
            let mut q = [0.0; 24];
            q[3] = 1.0; // FFJ3
            let t = r.fingertips_palm(&q)[0];
            assert!(t.y < -0.05, "{side:?}: {t}");
        }
    }

    #[test]
    fn posture_file_parses_and_rejects_bad_lines() {
        let q = parse_posture("lh_FFJ3 0.5\n# c\nTHJ4,1.0\n", "p.txt").unwrap();
        assert_eq!(q[3], 0.5);
        assert_eq!(q[20], 1.0);
        assert!(parse_posture("FFJ9 1\n", "p.txt")
            .unwrap_err()
            .contains("line 1"));
        assert!(parse_posture("FFJ3 x\n", "p.txt")
            .unwrap_err()
            .contains("not a number"));
        assert!(parse_posture("FFJ3 NaN\n", "p.txt")
            .unwrap_err()
            .contains("finite"));
    }
}
