//! Writes the project's URDF files from the published facts in [`super::joints`] and the
//! UR10e DH parameters in [`super::ur10e`].
//!
//! The files under `assets/robots/` are exactly this module's output (a test checks it), so
//! the robot the simulator loads is always the one documented here. Masses of finger links
//! are not published: the values below are plausible choices (tens of grams per phalanx,
//! 0.3 kg palm, 3 kg forearm) and are marked as such in the files.

use super::joints::{hand_facts, JointFact, Side};
use super::ur10e::{self, Dh};
use std::fmt::Write;

/// A collision primitive of a link, in the link frame.
#[derive(Debug, Clone, Copy)]
enum Prim {
    /// Full extents (x, y, z) at a centre.
    Box([f64; 3], [f64; 3]),
    /// Cylinder along z: radius, length, centre.
    Cyl(f64, f64, [f64; 3]),
    /// Sphere: radius, centre.
    Sphere(f64, [f64; 3]),
}

impl Prim {
    fn center(&self) -> [f64; 3] {
        match *self {
            Prim::Box(_, c) | Prim::Cyl(_, _, c) | Prim::Sphere(_, c) => c,
        }
    }

    /// Principal moments (about the centre) of a solid of mass `m`.
    fn inertia(&self, m: f64) -> [f64; 3] {
        match *self {
            Prim::Box([x, y, z], _) => [
                m * (y * y + z * z) / 12.0,
                m * (x * x + z * z) / 12.0,
                m * (x * x + y * y) / 12.0,
            ],
            Prim::Cyl(r, l, _) => {
                let t = m * (3.0 * r * r + l * l) / 12.0;
                [t, t, m * r * r / 2.0]
            }
            Prim::Sphere(r, _) => [0.4 * m * r * r; 3],
        }
    }

    fn mirrored(self, mirror: bool) -> Prim {
        if !mirror {
            return self;
        }
        let m = |c: [f64; 3]| [-c[0] + 0.0, c[1], c[2]];
        match self {
            Prim::Box(s, c) => Prim::Box(s, m(c)),
            Prim::Cyl(r, l, c) => Prim::Cyl(r, l, m(c)),
            Prim::Sphere(r, c) => Prim::Sphere(r, m(c)),
        }
    }
}

/// Finger phalanx radius (m), from ROBOT.md ("cylinders of radius about 7 mm").
pub const FINGER_RADIUS: f64 = 0.007;
/// Thumb phalanx radius (m): the thumb is a little thicker than the fingers.
pub const THUMB_RADIUS: f64 = 0.0085;

/// Mass (kg) and collision primitives of a hand link (canonical, unprefixed name), for the
/// RIGHT hand. The first primitive's centre is used as the centre of mass.
fn hand_link_body(link: &str) -> Option<(f64, Vec<Prim>)> {
    let r = FINGER_RADIUS;
    let t = THUMB_RADIUS;
    let finger = |seg: &str| -> Option<(f64, Vec<Prim>)> {
        match seg {
            "knuckle" => Some((0.008, vec![])),
            "proximal" => Some((0.030, vec![Prim::Cyl(r, 0.045, [0.0, 0.0, 0.0225])])),
            "middle" => Some((0.017, vec![Prim::Cyl(r, 0.025, [0.0, 0.0, 0.0125])])),
            // Rounded fingertip: a cylinder capped by a sphere whose top is the tip (26 mm).
            "distal" => Some((
                0.012,
                vec![
                    Prim::Cyl(r, 0.018, [0.0, 0.0, 0.009]),
                    Prim::Sphere(0.008, [0.0, 0.0, 0.018]),
                ],
            )),
            "tip" => None,
            _ => None,
        }
    };
    match link {
        "forearm" => Some((3.0, vec![Prim::Cyl(0.05, 0.18, [0.0, 0.0, 0.09])])),
        "wrist" => Some((0.1, vec![Prim::Box([0.04, 0.03, 0.022], [0.0, 0.0, 0.018])])),
        "palm" => Some((
            0.3,
            vec![
                Prim::Box([0.062, 0.007, 0.098], [0.011, 0.0085, 0.038]),
                Prim::Box([0.036, 0.017, 0.098], [-0.002, -0.0035, 0.038]),
                // Front of the palm under the first finger (one of the "few small ones").
                Prim::Box([0.024, 0.017, 0.07], [0.029, -0.0035, 0.052]),
            ],
        )),
        "lfmetacarpal" => Some((
            0.030,
            vec![Prim::Box([0.022, 0.017, 0.062], [0.0, -0.0035, 0.035])],
        )),
        "thbase" => Some((0.010, vec![])),
        "thproximal" => Some((0.040, vec![Prim::Cyl(t, 0.038, [0.0, 0.0, 0.019])])),
        "thhub" => Some((0.005, vec![])),
        "thmiddle" => Some((0.020, vec![Prim::Cyl(t, 0.032, [0.0, 0.0, 0.016])])),
        "thdistal" => Some((
            0.016,
            vec![
                Prim::Cyl(t, 0.0185, [0.0, 0.0, 0.00925]),
                Prim::Sphere(0.009, [0.0, 0.0, 0.0185]),
            ],
        )),
        "thtip" => None,
        l if l.len() > 2 && ["ff", "mf", "rf", "lf"].contains(&&l[..2]) => finger(&l[2..]),
        _ => None,
    }
}

fn fmt3(v: [f64; 3]) -> String {
    let f = |x: f64| {
        let s = format!("{x:.6}");
        let s = s.trim_end_matches('0').trim_end_matches('.').to_string();
        if s == "-0" {
            "0".to_string()
        } else {
            s
        }
    };
    format!("{} {} {}", f(v[0]), f(v[1]), f(v[2]))
}

fn write_link(out: &mut String, name: &str, mass: f64, prims: &[Prim], note: &str) {
    let _ = writeln!(out, "  <link name=\"{name}\">");
    if !note.is_empty() {
        let _ = writeln!(out, "    <!-- {note} -->");
    }
    if mass > 0.0 {
        let com = prims.first().map_or([0.0; 3], Prim::center);
        let i = prims
            .first()
            .map_or([1e-6; 3], |p| p.inertia(mass).map(|v| v.max(1e-7)));
        let _ = writeln!(out, "    <inertial>");
        let _ = writeln!(out, "      <origin xyz=\"{}\" rpy=\"0 0 0\"/>", fmt3(com));
        let _ = writeln!(out, "      <mass value=\"{mass}\"/>");
        let _ = writeln!(
            out,
            "      <inertia ixx=\"{:.3e}\" ixy=\"0\" ixz=\"0\" iyy=\"{:.3e}\" iyz=\"0\" izz=\"{:.3e}\"/>",
            i[0], i[1], i[2]
        );
        let _ = writeln!(out, "    </inertial>");
    }
    for p in prims {
        let geom = match *p {
            Prim::Box(s, _) => format!("<box size=\"{}\"/>", fmt3(s)),
            Prim::Cyl(r, l, _) => format!("<cylinder radius=\"{r}\" length=\"{l}\"/>"),
            Prim::Sphere(r, _) => format!("<sphere radius=\"{r}\"/>"),
        };
        for tag in ["visual", "collision"] {
            let _ = writeln!(out, "    <{tag}>");
            let _ = writeln!(
                out,
                "      <origin xyz=\"{}\" rpy=\"0 0 0\"/>",
                fmt3(p.center())
            );
            let _ = writeln!(out, "      <geometry>{geom}</geometry>");
            let _ = writeln!(out, "    </{tag}>");
        }
    }
    let _ = writeln!(out, "  </link>");
}

fn write_hand_joint(out: &mut String, prefix: &str, f: &JointFact) {
    let kind = if f.axis.is_some() {
        "revolute"
    } else {
        "fixed"
    };
    let _ = writeln!(out, "  <joint name=\"{prefix}{}\" type=\"{kind}\">", f.name);
    let _ = writeln!(out, "    <parent link=\"{prefix}{}\"/>", f.parent);
    let _ = writeln!(out, "    <child link=\"{prefix}{}\"/>", f.child);
    let _ = writeln!(
        out,
        "    <origin xyz=\"{}\" rpy=\"{}\"/>",
        fmt3(f.xyz),
        fmt3(f.rpy)
    );
    if let Some(a) = f.axis {
        let _ = writeln!(out, "    <axis xyz=\"{}\"/>", fmt3(a));
        let _ = writeln!(
            out,
            "    <limit lower=\"{}\" upper=\"{}\" effort=\"{}\" velocity=\"2.0\"/>",
            f.lower, f.upper, f.effort
        );
    }
    let _ = writeln!(out, "  </joint>");
}

/// Appends the links and joints of a hand (forearm root) to `out`.
fn write_hand_body(out: &mut String, side: Side) {
    let prefix = side.prefix();
    let facts = hand_facts(side);
    let mirror = side == Side::Left;
    let mut links = vec!["forearm"];
    for f in &facts {
        links.push(f.child);
    }
    for l in links {
        let (mass, prims) = hand_link_body(l).unwrap_or((0.0, vec![]));
        let prims: Vec<Prim> = prims.into_iter().map(|p| p.mirrored(mirror)).collect();
        let note = match l {
            "forearm" => "mass 3.0 kg (ROBOT.md); collision: a cylinder around the motor housing",
            "palm" => "mass 0.3 kg (ROBOT.md); collision boxes from ROBOT.md plus one under FF",
            "fftip" | "mftip" | "rftip" | "lftip" | "thtip" => {
                "fingertip frame (massless, fixed to the distal phalanx)"
            }
            _ if mass > 0.0 => "mass chosen by the project (plausible, not published)",
            _ => "",
        };
        write_link(out, &format!("{prefix}{l}"), mass, &prims, note);
    }
    for f in &facts {
        write_hand_joint(out, prefix, f);
    }
}

const HEADER: &str = "<?xml version=\"1.0\"?>\n<!-- Generated by grasp (src/robot/urdf_gen.rs) from the published kinematic facts in\n     shared/ROBOT.md. Regenerate with `grasp robot urdf`; do not edit by hand. -->\n";

/// The URDF text of a Shadow hand (`shadow_hand_left.urdf` / `shadow_hand_right.urdf`):
/// root link `{prefix}forearm`, 24 revolute joints and 5 fixed fingertip joints.
pub fn hand_urdf(side: Side) -> String {
    let mut out = String::from(HEADER);
    let _ = writeln!(out, "<robot name=\"shadow_hand_{}\">", side.name());
    write_hand_body(&mut out, side);
    out.push_str("</robot>\n");
    out
}

/// UR10e link masses (kg), base to wrist 3, from the manufacturer's published values.
const UR10E_MASSES: [f64; 7] = [4.0, 7.369, 13.051, 3.989, 2.1, 1.98, 0.615];
const UR10E_LINKS: [&str; 7] = [
    "base_link",
    "shoulder_link",
    "upper_arm_link",
    "forearm_link",
    "wrist_1_link",
    "wrist_2_link",
    "wrist_3_link",
];

/// The URDF text of the UR10e (`ur10e.urdf`) with the LEFT Shadow hand on its flange.
///
/// Joint frames follow the standard DH convention exactly (joint i rotates about z of DH
/// frame i-1; the fixed origins are `Tz(d) Tx(a) Rx(alpha)` of the previous row), so the
/// URDF's forward kinematics equals [`ur10e::fk`]. This differs from the manufacturer's
/// URDF frames (which rotate the base by pi about z and use other link frames) but gives
/// the same flange pose as the robot controller for the same joint angles.
///
/// Mounting: the hand's forearm frame coincides with the flange frame `tool0` (z out of the
/// flange, along the forearm toward the fingers); no adapter offset.
pub fn ur10e_with_hand_urdf() -> String {
    let dh = ur10e::UR10E;
    let mut out = String::from(HEADER);
    out.push_str("<robot name=\"ur10e_shadow_hand_left\">\n");
    for (k, name) in UR10E_LINKS.iter().enumerate() {
        // A rough collision cylinder along the link's DH segment is enough for the arm,
        // which never touches the object in the grasping task.
        let prim = arm_link_prim(&dh, k);
        write_link(
            &mut out,
            name,
            UR10E_MASSES[k],
            &[prim],
            "UR10e: published mass; collision is a rough cylinder",
        );
    }
    write_link(&mut out, "tool0", 0.0, &[], "flange frame");
    let names = ur10e::JOINT_NAMES;
    for k in 0..6 {
        let (xyz, rpy) = if k == 0 {
            ([0.0; 3], [0.0; 3])
        } else {
            dh_origin(&dh, k - 1)
        };
        let _ = writeln!(out, "  <joint name=\"{}\" type=\"revolute\">", names[k]);
        let _ = writeln!(out, "    <parent link=\"{}\"/>", UR10E_LINKS[k]);
        let _ = writeln!(out, "    <child link=\"{}\"/>", UR10E_LINKS[k + 1]);
        let _ = writeln!(
            out,
            "    <origin xyz=\"{}\" rpy=\"{}\"/>",
            fmt3(xyz),
            fmt3(rpy)
        );
        let _ = writeln!(out, "    <axis xyz=\"0 0 1\"/>");
        let _ = writeln!(
            out,
            "    <limit lower=\"{:.6}\" upper=\"{:.6}\" effort=\"{}\" velocity=\"{:.6}\"/>",
            -ur10e::JOINT_LIMIT,
            ur10e::JOINT_LIMIT,
            ur10e::EFFORT[k],
            ur10e::VELOCITY[k]
        );
        let _ = writeln!(out, "  </joint>");
    }
    let (xyz, rpy) = dh_origin(&dh, 5);
    let _ = writeln!(out, "  <joint name=\"flange\" type=\"fixed\">");
    let _ = writeln!(out, "    <parent link=\"wrist_3_link\"/>");
    let _ = writeln!(out, "    <child link=\"tool0\"/>");
    let _ = writeln!(
        out,
        "    <origin xyz=\"{}\" rpy=\"{}\"/>",
        fmt3(xyz),
        fmt3(rpy)
    );
    let _ = writeln!(out, "  </joint>");
    write_hand_body(&mut out, Side::Left);
    out.push_str(
        "  <!-- Mounting: the hand's forearm frame is the flange frame tool0. -->\n  <joint name=\"tool0_to_lh_forearm\" type=\"fixed\">\n    <parent link=\"tool0\"/>\n    <child link=\"lh_forearm\"/>\n    <origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>\n  </joint>\n",
    );
    out.push_str("</robot>\n");
    out
}

/// The fixed origin after DH row `k`: `Tz(d) Tx(a) Rx(alpha)` as URDF xyz/rpy.
fn dh_origin(dh: &Dh, k: usize) -> ([f64; 3], [f64; 3]) {
    ([dh.a[k], 0.0, dh.d[k]], [dh.alpha[k], 0.0, 0.0])
}

fn arm_link_prim(dh: &Dh, k: usize) -> Prim {
    let r = match k {
        0..=2 => 0.075,
        3 => 0.06,
        _ => 0.045,
    };
    match k {
        // Links whose DH segment runs along x (upper arm, forearm).
        2 | 3 => {
            let a = dh.a[k - 1];
            Prim::Cyl(r, a.abs().max(0.05), [a / 2.0, 0.0, 0.0])
        }
        0 => Prim::Cyl(r, 0.05, [0.0, 0.0, 0.025]),
        _ => Prim::Sphere(r, [0.0, 0.0, 0.0]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shipped_urdfs_are_the_generator_output() {
        let root = env!("CARGO_MANIFEST_DIR");
        for (file, text) in [
            ("shadow_hand_left.urdf", hand_urdf(Side::Left)),
            ("shadow_hand_right.urdf", hand_urdf(Side::Right)),
            ("ur10e.urdf", ur10e_with_hand_urdf()),
        ] {
            let path = format!("{root}/assets/robots/{file}");
            let shipped = std::fs::read_to_string(&path).unwrap_or_default();
            assert!(
                shipped == text,
                "{path} differs from the generator: run `cargo run -- robot urdf --all --out-dir assets/robots`"
            );
        }
    }

    #[test]
    fn cylinder_inertia_hand_computed() {
        // m = 0.03, r = 0.007, L = 0.045: Ixx = m (3 r^2 + L^2) / 12, Izz = m r^2 / 2.
        let i = Prim::Cyl(0.007, 0.045, [0.0; 3]).inertia(0.03);
        assert!((i[0] - 0.03 * (3.0 * 49e-6 + 0.045 * 0.045) / 12.0).abs() < 1e-15);
        assert!((i[2] - 0.03 * 49e-6 / 2.0).abs() < 1e-15);
    }
}
