//! [`RosHandArm`]: the Shadow hand's ROS 1 driver and the UR10e behind [`HandArm`],
//! through a rosbridge v2 server (JSON over a websocket; `ws://` only, no TLS).
//!
//! The protocol subset used: the client sends `{"op": "subscribe", "topic", "type"}` for
//! the sensor topics, `{"op": "advertise", "topic", "type"}` for the command topics and
//! `{"op": "publish", "topic", "msg"}` for every command; the server sends
//! `{"op": "publish", "topic", "msg"}` for every sensor message.
//!
//! Topics (all configurable in [`RosConfig`], defaults are the Shadow driver's for a left
//! hand `lh_` on an arm `la_`):
//! - `/joint_states` (`sensor_msgs/JointState`): hand joint angles `lh_FFJ4` ... and
//!   efforts (the driver reports the tendon force per joint; a coupled actuator's reading
//!   is the sum of its J1 and J2 entries), and the arm joints `la_shoulder_pan_joint` ...;
//! - `/lh/tactile` (`sr_robot_msgs/ShadowPST`): field `pressure`, five values FF, MF, RF,
//!   LF, TH;
//! - `/lh_trajectory_controller/command` (`trajectory_msgs/JointTrajectory`): hand
//!   targets, one point reached in `hand_point_time_s`;
//! - `/la_trajectory_controller/command` (`trajectory_msgs/JointTrajectory`): arm
//!   motions, one point at the end of the motion.
//!
//! Reading stamps are the backend clock (seconds since the connection) at which the
//! newest `joint_states` message arrived, so when the driver stops publishing the stamps
//! go stale and [`SafeHandArm`](super::safety::SafeHandArm)'s watchdog stops the robot.
//! A lift is computed from the measured arm joints: UR10e forward kinematics, the flange
//! raised by the height (the arm base is assumed upright), inverse kinematics.
//! [`HandArm::stop`] commands the hand and the arm to hold their measured positions.

use super::{check_duration, ArmMotion, HandArm, HwError, RawSensors};
use crate::robot::joints::HAND_JOINTS;
use crate::robot::joints::{N_JOINTS, N_TACTILE};
use crate::robot::ur10e;
use nalgebra::{Isometry3, Translation3};
use serde_json::{json, Value};
use std::io::ErrorKind;
use std::net::{TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};
use tungstenite::client::IntoClientRequest;
use tungstenite::{Message, WebSocket};

/// Topic names, message types and timing of the ROS backend.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RosConfig {
    /// Joint states of hand and arm.
    pub joint_states_topic: String,
    /// Fingertip sensor topic.
    pub tactile_topic: String,
    /// Its message type.
    pub tactile_type: String,
    /// The array field of the tactile message with the five fingertip values.
    pub tactile_field: String,
    /// Hand trajectory command topic.
    pub hand_command_topic: String,
    /// Arm trajectory command topic.
    pub arm_command_topic: String,
    /// Prefix of the hand joint names (`lh_` left, `rh_` right).
    pub hand_prefix: String,
    /// Prefix of the arm joint names.
    pub arm_prefix: String,
    /// Time to reach a hand target (s).
    pub hand_point_time_s: f64,
    /// Duration of an arm joint motion (s).
    pub arm_motion_time_s: f64,
    /// How long a read waits for the first complete data, and the connection timeout (s).
    pub timeout_s: f64,
}

impl Default for RosConfig {
    fn default() -> Self {
        RosConfig {
            joint_states_topic: "/joint_states".into(),
            tactile_topic: "/lh/tactile".into(),
            tactile_type: "sr_robot_msgs/ShadowPST".into(),
            tactile_field: "pressure".into(),
            hand_command_topic: "/lh_trajectory_controller/command".into(),
            arm_command_topic: "/la_trajectory_controller/command".into(),
            hand_prefix: "lh_".into(),
            arm_prefix: "la_".into(),
            hand_point_time_s: 0.1,
            arm_motion_time_s: 4.0,
            timeout_s: 1.0,
        }
    }
}

/// The latest sensor state received.
#[derive(Debug, Clone, Default)]
struct State {
    hand_q: Option<[f64; N_JOINTS]>,
    hand_effort: [f64; N_JOINTS],
    arm_q: Option<[f64; 6]>,
    tactile: Option<[f64; N_TACTILE]>,
    stamp: f64,
}

/// The robot through rosbridge (see the module docs).
pub struct RosHandArm {
    ws: WebSocket<TcpStream>,
    t0: Instant,
    dec: RosDecoder,
}

/// Decodes the rosbridge messages the server sends into the latest sensor state: what
/// [`RosHandArm`] does with every message it receives, apart from the connection (so it
/// can be tested, and fuzzed, on its own). A malformed message is an error naming the
/// topic and field; other ops and topics are ignored.
#[derive(Debug, Clone)]
pub struct RosDecoder {
    cfg: RosConfig,
    state: State,
    hand_names: Vec<String>,
    arm_names: Vec<String>,
}

impl RosDecoder {
    /// A decoder for the topics and joint-name prefixes of `cfg`, with no data yet.
    pub fn new(cfg: RosConfig) -> Self {
        RosDecoder {
            hand_names: HAND_JOINTS
                .iter()
                .map(|j| format!("{}{j}", cfg.hand_prefix))
                .collect(),
            arm_names: ur10e::JOINT_NAMES
                .iter()
                .map(|j| format!("{}{j}", cfg.arm_prefix))
                .collect(),
            cfg,
            state: State::default(),
        }
    }

    /// The newest hand joint angles, if a complete `joint_states` message arrived.
    pub fn hand_q(&self) -> Option<[f64; N_JOINTS]> {
        self.state.hand_q
    }

    /// The newest tactile values, if any arrived.
    pub fn tactile(&self) -> Option<[f64; N_TACTILE]> {
        self.state.tactile
    }

    /// The newest arm joint angles, if any arrived.
    pub fn arm_q(&self) -> Option<[f64; 6]> {
        self.state.arm_q
    }

    /// Handles one message `text` received at backend time `now` (s).
    pub fn handle(&mut self, text: &str, now: f64) -> Result<(), HwError> {
        let v: Value = serde_json::from_str(text).map_err(|e| HwError::InvalidReading {
            field: "rosbridge message".into(),
            detail: e.to_string(),
        })?;
        if v["op"] != "publish" {
            return Ok(());
        }
        let topic = v["topic"].as_str().unwrap_or_default();
        let msg = &v["msg"];
        if topic == self.cfg.joint_states_topic {
            self.joint_states(msg, now)
        } else if topic == self.cfg.tactile_topic {
            let field = &self.cfg.tactile_field;
            let vals = numbers(&msg[field.as_str()], &format!("{topic}.{field}"))?;
            if vals.len() != N_TACTILE {
                return Err(HwError::InvalidReading {
                    field: format!("{topic}.{field}"),
                    detail: format!("{} values, expected 5 (FF, MF, RF, LF, TH)", vals.len()),
                });
            }
            self.state.tactile = Some(std::array::from_fn(|k| vals[k]));
            Ok(())
        } else {
            Ok(())
        }
    }

    fn joint_states(&mut self, msg: &Value, now: f64) -> Result<(), HwError> {
        let topic = &self.cfg.joint_states_topic;
        let names: Vec<&str> = msg["name"]
            .as_array()
            .map(|a| a.iter().filter_map(Value::as_str).collect())
            .unwrap_or_default();
        let pos = numbers(&msg["position"], &format!("{topic}.position"))?;
        let eff = if msg["effort"].as_array().is_some_and(|a| !a.is_empty()) {
            numbers(&msg["effort"], &format!("{topic}.effort"))?
        } else {
            vec![0.0; names.len()]
        };
        if pos.len() != names.len() || eff.len() != names.len() {
            return Err(HwError::InvalidReading {
                field: topic.clone(),
                detail: format!(
                    "{} names, {} positions, {} efforts",
                    names.len(),
                    pos.len(),
                    eff.len()
                ),
            });
        }
        let find = |n: &str| names.iter().position(|m| *m == n);
        let hand: Option<Vec<usize>> = self.hand_names.iter().map(|n| find(n)).collect();
        if let Some(idx) = hand {
            self.state.hand_q = Some(std::array::from_fn(|k| pos[idx[k]]));
            self.state.hand_effort = std::array::from_fn(|k| eff[idx[k]]);
            self.state.stamp = now;
        }
        let arm: Option<Vec<usize>> = self.arm_names.iter().map(|n| find(n)).collect();
        if let Some(idx) = arm {
            self.state.arm_q = Some(std::array::from_fn(|k| pos[idx[k]]));
        }
        Ok(())
    }
}

fn disconnected(e: impl std::fmt::Display) -> HwError {
    HwError::Disconnected(e.to_string())
}

fn duration_json(s: f64) -> Value {
    let secs = s.floor();
    json!({"secs": secs as i64, "nsecs": ((s - secs) * 1e9).round() as i64})
}

impl RosHandArm {
    /// Connects to the rosbridge server at `url` (`ws://host:port`), subscribes to the
    /// sensor topics and advertises the command topics.
    pub fn connect(url: &str, cfg: RosConfig) -> Result<RosHandArm, HwError> {
        if !(cfg.timeout_s.is_finite() && cfg.timeout_s > 0.0) {
            return Err(HwError::InvalidCommand {
                field: "timeout_s".into(),
                detail: format!("{} must be positive", cfg.timeout_s),
            });
        }
        let req = url
            .into_client_request()
            .map_err(|e| disconnected(format!("bad rosbridge url '{url}': {e}")))?;
        if req.uri().scheme_str() != Some("ws") {
            return Err(disconnected(format!(
                "rosbridge url '{url}': only ws:// is supported"
            )));
        }
        let host = req.uri().host().unwrap_or("localhost").to_string();
        let port = req.uri().port_u16().unwrap_or(80);
        let addr = (host.as_str(), port)
            .to_socket_addrs()
            .map_err(|e| disconnected(format!("cannot resolve {host}:{port}: {e}")))?
            .next()
            .ok_or_else(|| disconnected(format!("{host}:{port} has no address")))?;
        let timeout = Duration::try_from_secs_f64(cfg.timeout_s.min(86_400.0))
            .unwrap_or(Duration::from_secs(1));
        let stream = TcpStream::connect_timeout(&addr, timeout)
            .map_err(|e| disconnected(format!("cannot connect to {addr}: {e}")))?;
        stream.set_read_timeout(Some(timeout))?;
        let (ws, _) = tungstenite::client(req, stream)
            .map_err(|e| disconnected(format!("websocket handshake with {url} failed: {e}")))?;
        let mut arm = RosHandArm {
            ws,
            t0: Instant::now(),
            dec: RosDecoder::new(cfg),
        };
        arm.ws
            .get_mut()
            .set_read_timeout(Some(Duration::from_millis(2)))?;
        let c = arm.dec.cfg.clone();
        arm.send(json!({"op": "subscribe", "topic": c.joint_states_topic, "type": "sensor_msgs/JointState", "queue_length": 1}))?;
        arm.send(json!({"op": "subscribe", "topic": c.tactile_topic, "type": c.tactile_type, "queue_length": 1}))?;
        arm.send(json!({"op": "advertise", "topic": c.hand_command_topic, "type": "trajectory_msgs/JointTrajectory"}))?;
        arm.send(json!({"op": "advertise", "topic": c.arm_command_topic, "type": "trajectory_msgs/JointTrajectory"}))?;
        Ok(arm)
    }

    /// The configuration.
    pub fn config(&self) -> &RosConfig {
        &self.dec.cfg
    }

    /// The last measured arm joints, if received.
    pub fn arm_joints(&self) -> Option<[f64; 6]> {
        self.dec.state.arm_q
    }

    fn send(&mut self, v: Value) -> Result<(), HwError> {
        self.ws
            .send(Message::text(v.to_string()))
            .map_err(disconnected)
    }

    /// Handles every message already received; returns when none is pending.
    fn pump(&mut self) -> Result<(), HwError> {
        loop {
            match self.ws.read() {
                Ok(Message::Text(t)) => {
                    let now = self.now();
                    self.dec.handle(t.as_str(), now)?
                }
                Ok(Message::Close(_)) => {
                    return Err(disconnected("rosbridge closed the connection"))
                }
                Ok(_) => {}
                Err(tungstenite::Error::Io(e))
                    if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) =>
                {
                    return Ok(())
                }
                Err(e) => return Err(disconnected(format!("rosbridge connection lost: {e}"))),
            }
        }
    }

    fn trajectory(
        &mut self,
        topic: String,
        names: Vec<String>,
        q: &[f64],
        t: f64,
    ) -> Result<(), HwError> {
        let msg = json!({
            "header": {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""},
            "joint_names": names,
            "points": [{
                "positions": q,
                "velocities": [],
                "accelerations": [],
                "effort": [],
                "time_from_start": duration_json(t),
            }],
        });
        self.send(json!({"op": "publish", "topic": topic, "msg": msg}))
    }

    /// Pumps messages for `seconds` of the backend clock.
    fn pump_for(&mut self, seconds: f64) -> Result<(), HwError> {
        let end = self.now() + seconds;
        loop {
            self.pump()?;
            if self.now() >= end {
                return Ok(());
            }
        }
    }
}

impl Drop for RosHandArm {
    /// Closes the websocket with the close handshake (reading until the server's close
    /// frame, at most `timeout_s`), so that nothing the client sent is lost to a reset.
    fn drop(&mut self) {
        if self.ws.close(None).is_err() {
            return;
        }
        let end = self.now() + self.dec.cfg.timeout_s;
        while self.now() < end {
            match self.ws.read() {
                Ok(_) => {}
                Err(tungstenite::Error::Io(e))
                    if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {}
                Err(_) => return,
            }
        }
    }
}

fn numbers(v: &Value, field: &str) -> Result<Vec<f64>, HwError> {
    let arr = v.as_array().ok_or_else(|| HwError::InvalidReading {
        field: field.into(),
        detail: "missing or not an array".into(),
    })?;
    arr.iter()
        .enumerate()
        .map(|(k, x)| {
            x.as_f64().ok_or_else(|| HwError::InvalidReading {
                field: format!("{field}[{k}]"),
                detail: format!("{x} is not a number"),
            })
        })
        .collect()
}

impl HandArm for RosHandArm {
    /// The newest data; waits up to `timeout_s` for the first complete set (hand joint
    /// states and tactile values), then [`HwError::Timeout`].
    fn read(&mut self) -> Result<RawSensors, HwError> {
        let start = self.now();
        loop {
            self.pump()?;
            if let (Some(q), Some(t)) = (self.dec.state.hand_q, self.dec.state.tactile) {
                return Ok(RawSensors {
                    stamp: self.dec.state.stamp,
                    joint_angles: q,
                    tactile_raw: t,
                    tendon_raw: crate::robot::joints::actuator_sums(&self.dec.state.hand_effort),
                });
            }
            let waited = self.now() - start;
            if waited > self.dec.cfg.timeout_s {
                let what = if self.dec.state.hand_q.is_none() {
                    format!("hand joint states on {}", self.dec.cfg.joint_states_topic)
                } else {
                    format!("tactile data on {}", self.dec.cfg.tactile_topic)
                };
                return Err(HwError::Timeout {
                    what,
                    waited_s: waited,
                });
            }
        }
    }

    fn command_hand(&mut self, targets: &[f64; N_JOINTS]) -> Result<(), HwError> {
        if let Some(k) = targets.iter().position(|v| !v.is_finite()) {
            return Err(HwError::InvalidCommand {
                field: format!("targets[{k}] ({})", HAND_JOINTS[k]),
                detail: "not finite; nothing was sent".into(),
            });
        }
        let (topic, names, t) = (
            self.dec.cfg.hand_command_topic.clone(),
            self.dec.hand_names.clone(),
            self.dec.cfg.hand_point_time_s,
        );
        self.trajectory(topic, names, targets, t)
    }

    /// Publishes the arm trajectory and waits for the motion's duration.
    fn move_arm(&mut self, motion: &ArmMotion) -> Result<(), HwError> {
        motion.validate()?;
        let (q, t) = match *motion {
            ArmMotion::Joints(q) => (q, self.dec.cfg.arm_motion_time_s),
            ArmMotion::Lift {
                height_m,
                duration_s,
            } => {
                self.pump()?;
                let q0 = self.dec.state.arm_q.ok_or_else(|| HwError::Timeout {
                    what: format!("arm joint states on {}", self.dec.cfg.joint_states_topic),
                    waited_s: 0.0,
                })?;
                let up = Isometry3::from_parts(
                    Translation3::new(0.0, 0.0, height_m),
                    nalgebra::UnitQuaternion::identity(),
                ) * ur10e::fk(&q0);
                let q = ur10e::ik(&up, &q0).map_err(|e| HwError::InvalidCommand {
                    field: "lift".into(),
                    detail: e.to_string(),
                })?;
                (q, duration_s)
            }
        };
        let (topic, names) = (
            self.dec.cfg.arm_command_topic.clone(),
            self.dec.arm_names.clone(),
        );
        self.trajectory(topic, names, &q, t)?;
        self.pump_for(t)
    }

    fn stop(&mut self) -> Result<(), HwError> {
        self.pump()?;
        if let Some(q) = self.dec.state.hand_q {
            let (topic, names) = (
                self.dec.cfg.hand_command_topic.clone(),
                self.dec.hand_names.clone(),
            );
            self.trajectory(topic, names, &q, self.dec.cfg.hand_point_time_s)?;
        }
        if let Some(q) = self.dec.state.arm_q {
            let (topic, names) = (
                self.dec.cfg.arm_command_topic.clone(),
                self.dec.arm_names.clone(),
            );
            self.trajectory(topic, names, &q, self.dec.cfg.hand_point_time_s)?;
        }
        Ok(())
    }

    fn now(&self) -> f64 {
        self.t0.elapsed().as_secs_f64()
    }

    /// Keeps receiving messages while `seconds` pass.
    fn wait(&mut self, seconds: f64) -> Result<(), HwError> {
        check_duration(seconds)?;
        self.pump_for(seconds)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_split_into_secs_and_nsecs() {
        assert_eq!(
            duration_json(2.25),
            json!({"secs": 2, "nsecs": 250_000_000})
        );
    }
}
