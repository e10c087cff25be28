//! What the simulator reads off its state: the object's pose, box, speed and contact
//! forces, the hand's joint state, efforts and sensors, and the privileged geometry of
//! the asymmetric critic. Nothing here changes the world.

use super::*;

impl HandSim {
    /// The object body's origin in the world (m): the centre of its bounding box (see
    /// [`crate::sim::object`]); `rest_height()` above the table top when it rests upright.
    pub fn object_position(&self) -> Vector3<f64> {
        self.sets
            .bodies
            .get(self.object_body)
            .map(|rb| vec_f64(rb.translation()))
            .unwrap_or_else(Vector3::zeros)
    }

    /// The object's pose: position (m) and unit quaternion (x, y, z, w), as f32 bits of
    /// the physics state (for exact comparisons).
    pub fn object_pose_raw(&self) -> [f32; 7] {
        self.sets
            .bodies
            .get(self.object_body)
            .map(|rb| {
                let p = rb.position();
                [
                    p.translation.x,
                    p.translation.y,
                    p.translation.z,
                    p.rotation.x,
                    p.rotation.y,
                    p.rotation.z,
                    p.rotation.w,
                ]
            })
            .unwrap_or([f32::NAN; 7])
    }

    /// Tilt of the object (rad): the angle between its body z axis and the world z axis.
    pub fn object_tilt(&self) -> f64 {
        let [_, _, _, x, y, _, _] = self.object_pose_raw().map(f64::from);
        // z component of the rotated z axis: 1 - 2 (x^2 + y^2).
        (1.0 - 2.0 * (x * x + y * y)).clamp(-1.0, 1.0).acos()
    }

    /// World pose of a collider from its parent body's pose (valid right after a reset,
    /// before the first step has synchronised the collider positions).
    pub(in crate::sim) fn collider_world_pose(&self, h: ColliderHandle) -> Option<Pose> {
        let c = self.sets.colliders.get(h)?;
        let local = c.position_wrt_parent().copied().unwrap_or(Pose::IDENTITY);
        let body = self.sets.bodies.get(c.parent()?)?;
        Some(*body.position() * local)
    }

    /// Whether any hand collider overlaps the object in the current configuration (exact
    /// shape intersection tests). Used after a reset so that the hand starts clear of the
    /// object instead of inside it.
    pub fn hand_overlaps_object(&self) -> bool {
        let (Some(obj), Some(obj_pose)) = (
            self.sets.colliders.get(self.object_collider),
            self.collider_world_pose(self.object_collider),
        ) else {
            return false;
        };
        self.hand_colliders.iter().any(|&h| {
            match (self.sets.colliders.get(h), self.collider_world_pose(h)) {
                (Some(c), Some(pose)) => rapier3d::parry::query::intersection_test(
                    &pose,
                    c.shape(),
                    &obj_pose,
                    obj.shape(),
                )
                .is_ok_and(|i| i.intersecting),
                _ => false,
            }
        })
    }

    /// Height of the object's lowest point above the table top (m). For a compound
    /// object, the lowest of its convex parts' vertices in the world frame: the
    /// compound's own bounding box is its body-frame box turned with the object, which
    /// lies below the object (under the table) once it is tilted.
    pub fn object_lowest_z(&self) -> f64 {
        self.object_aabb().map_or(f64::NAN, |(lo, _)| lo.z)
    }

    /// The object's world bounding box (m): lowest and highest corners. For a compound
    /// object, the union of its convex parts' boxes in the world frame (tight when it is
    /// tilted, unlike the compound's own box; see [`HandSim::object_lowest_z`]).
    pub fn object_aabb(&self) -> Option<(Point3<f64>, Point3<f64>)> {
        let c = self.sets.colliders.get(self.object_collider)?;
        let aabb = match c.shape().as_compound() {
            Some(compound) => compound
                .shapes()
                .iter()
                .map(|(part_pose, part)| part.compute_aabb(&(c.position() * part_pose)))
                .reduce(|a, b| a.merged(&b))?,
            None => c.compute_aabb(),
        };
        let p = |v: Vector| Point3::new(v.x as f64, v.y as f64, v.z as f64);
        Some((p(aabb.mins), p(aabb.maxs)))
    }

    /// The object's pose (m, unit quaternion) in f64.
    pub fn object_pose(&self) -> Option<Isometry3<f64>> {
        self.sets
            .bodies
            .get(self.object_body)
            .map(|rb| pose_f64(rb.position()))
    }

    /// The object's linear (m/s) and angular (rad/s) speed.
    pub fn object_speed(&self) -> (f64, f64) {
        self.sets
            .bodies
            .get(self.object_body)
            .map_or((f64::NAN, f64::NAN), |rb| {
                (vec_f64(rb.linvel()).norm(), vec_f64(rb.angvel()).norm())
            })
    }

    /// The lift coordinate (m above its start).
    pub fn lift_position(&self) -> f64 {
        self.multibody()
            .and_then(|mb| mb.link(self.lift_link))
            .map(|l| l.joint().coords()[0] as f64)
            .unwrap_or(f64::NAN)
    }

    /// World pose of the body carrying URDF link `link` (test helper).
    #[cfg(test)]
    pub(super) fn link_body_pose(&self, link: usize) -> Option<Isometry3<f64>> {
        let mb = self.multibody()?;
        let hj = self
            .robot
            .joints
            .iter()
            .position(|j| j.child == link)
            .and_then(|ji| self.robot.hand.joints.iter().position(|&x| x == ji))?;
        let l = mb.link(self.joints[hj].link)?;
        Some(pose_f64(
            self.sets.bodies.get(l.rigid_body_handle())?.position(),
        ))
    }

    fn multibody(&self) -> Option<&Multibody> {
        let link = self.sets.multibody_joints.rigid_body_link(self.mb_root)?;
        self.sets.multibody_joints.get_multibody(link.multibody)
    }

    /// Joint angles (rad) and velocities (rad/s) of the 24 hand joints, paper order.
    pub fn joint_state(&self) -> ([f64; 24], [f64; 24]) {
        let mut q = [0.0; 24];
        let mut qd = [0.0; 24];
        if let Some(mb) = self.multibody() {
            for (n, hj) in self.joints.iter().enumerate() {
                if let Some(l) = mb.link(hj.link) {
                    q[n] = l.joint().coords()[3] as f64;
                    qd[n] = mb.joint_velocity(l)[0] as f64;
                }
            }
        }
        (q, qd)
    }

    /// Privileged geometry for an asymmetric critic (never a sensor of the robot): the
    /// palm's and the object's world poses, the object's linear and angular velocity, and
    /// for each distal phalanx (FF, MF, RF, LF, TH) and the palm the centre of its first
    /// collider with the nearest point of the object's surface to it (parry's projection,
    /// millimetre-accurate on hulls). `None` before the first reset.
    pub fn critic_geometry(&self) -> Option<CriticGeometry> {
        let obj = self.sets.colliders.get(self.object_collider)?;
        let obj_pose = self.collider_world_pose(self.object_collider)?;
        let rb = self.sets.bodies.get(self.object_body)?;
        let palm = self
            .collider_links
            .iter()
            .find(|(_, name)| name.ends_with("palm"))
            .map(|(h, _)| *h)?;
        let palm_body = self
            .sets
            .bodies
            .get(self.sets.colliders.get(palm)?.parent()?)?;
        let near = |h: ColliderHandle| -> Option<(Point3<f64>, Point3<f64>)> {
            let c = self.collider_world_pose(h)?.translation;
            let p = obj.shape().project_point(&obj_pose, c, false).point;
            Some((Point3::from(vec_f64(c)), Point3::from(vec_f64(p))))
        };
        let mut nearest = [(Point3::origin(), Point3::origin()); 6];
        for (f, n) in nearest.iter_mut().enumerate() {
            let h = if f < 5 {
                *self.distal_colliders[f].first()?
            } else {
                palm
            };
            *n = near(h)?;
        }
        Some(CriticGeometry {
            palm: pose_f64(palm_body.position()),
            object: pose_f64(rb.position()),
            object_linvel: vec_f64(rb.linvel()),
            object_angvel: vec_f64(rb.angvel()),
            nearest,
        })
    }

    /// Normal force (N) between the object and each distal phalanx (FF, MF, RF, LF, TH):
    /// the summed contact impulses of the last step divided by the step.
    pub fn tip_forces(&self) -> [f64; 5] {
        std::array::from_fn(|f| {
            self.distal_colliders[f]
                .iter()
                .map(|c| self.pair_force(*c, self.object_collider))
                .sum()
        })
    }

    /// Normal force (N) between two colliders: summed contact impulses / dt.
    pub(super) fn pair_force(&self, c1: ColliderHandle, c2: ColliderHandle) -> f64 {
        self.narrow_phase
            .contact_pair(c1, c2)
            .map_or(0.0, |p| p.total_impulse_magnitude() as f64)
            / self.cfg.dt
    }

    /// Normal force (N) between the object and the table top.
    pub fn table_object_force(&self) -> f64 {
        self.pair_force(self.table, self.object_collider)
            + self.pair_force(self.table, self.object_hull)
    }

    /// Total normal force (N) between the object and any hand collider.
    pub fn hand_object_force(&self) -> f64 {
        self.hand_colliders
            .iter()
            .map(|c| self.pair_force(*c, self.object_collider))
            .sum()
    }

    /// The 24 joint efforts (N m) the motors apply and report: the PD law clamped to the
    /// effort limit.
    pub fn joint_efforts(&self) -> [f64; 24] {
        let (q, qd) = self.joint_state();
        std::array::from_fn(|n| {
            let hj = &self.joints[n];
            pd_effort(hj.kp, hj.kd, self.targets[n], q[n], qd[n], hj.effort)
        })
    }

    /// All sensor readings now.
    pub fn sensors(&self) -> Sensors {
        let (q, qdot) = self.joint_state();
        let e24 = self.joint_efforts();
        let tip_force = self.tip_forces();
        let th = self.cfg.sensors.tactile_threshold;
        let tactile = tip_force.map(|f| u8::from(f > th));
        let effort = crate::robot::joints::actuator_sums(&e24);
        let scale = self.cfg.sensors.torque_scale;
        let torque_level =
            effort.map(|e| torque_level(e * scale, &self.cfg.sensors.torque_thresholds));
        Sensors {
            tactile,
            tip_force,
            effort,
            torque_level,
            q,
            qdot,
        }
    }

    /// Whether a lift is decided as a failure: every hand collider is above the object's
    /// highest point by `DECIDED_CLEARANCE`. The hand only rises from here, so it can no
    /// longer touch, let alone carry, the object.
    pub(super) fn dropped(&self) -> bool {
        let Some(obj) = self.sets.colliders.get(self.object_collider) else {
            return false;
        };
        let top = obj.compute_aabb().maxs.z as f64;
        self.hand_colliders.iter().all(|&h| {
            self.sets
                .colliders
                .get(h)
                .is_some_and(|c| c.compute_aabb().mins.z as f64 > top + DECIDED_CLEARANCE)
        })
    }
}
