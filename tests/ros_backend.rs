//! The ros backend against a local rosbridge-protocol peer: a websocket server on
//! 127.0.0.1 in a thread that records the client's subscribe/advertise/publish ops and
//! publishes canned `joint_states` and tactile messages.
#![cfg(feature = "ros")]

use grasp::hardware::ros::{RosConfig, RosHandArm};
use grasp::hardware::safety::{SafeHandArm, SafetyConfig};
use grasp::hardware::{ArmMotion, HandArm, HwError};
use grasp::robot::joints::HAND_JOINTS;
use grasp::robot::{ur10e, Robot, Side};
use serde_json::{json, Value};
use std::net::TcpListener;
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use tungstenite::Message;

/// What the peer does after the client subscribed.
#[derive(Clone, Copy)]
enum Script {
    /// Publish every 10 ms until the client goes away.
    Publish,
    /// Never publish.
    Silent,
    /// Publish for this long, then stay connected but silent.
    PublishThenSilent(f64),
    /// Publish for this long, then close the connection.
    PublishThenClose(f64),
    /// Publish one malformed joint_states message.
    Malformed,
}

/// Mid-range angles of the left hand (inside every limit), distinct per joint.
fn hand_q() -> [f64; 24] {
    let l = Robot::builtin(Side::Left).hand_limits();
    std::array::from_fn(|k| 0.5 * (l[k].0 + l[k].1) + 0.001 * k as f64)
}

fn assert_close(a: &[f64], b: &[f64]) {
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b) {
        assert!((x - y).abs() < 1e-12, "{a:?} vs {b:?}");
    }
}

fn hand_effort() -> [f64; 24] {
    std::array::from_fn(|k| 10.0 * k as f64)
}

const ARM_Q: [f64; 6] = ur10e::HOME;

/// joint_states with the arm first and the hand joints in reverse order.
fn joint_states() -> Value {
    let mut names: Vec<String> = ur10e::JOINT_NAMES
        .iter()
        .map(|n| format!("la_{n}"))
        .collect();
    let mut pos: Vec<f64> = ARM_Q.to_vec();
    let mut eff = vec![0.0; 6];
    for k in (0..24).rev() {
        names.push(format!("lh_{}", HAND_JOINTS[k]));
        pos.push(hand_q()[k]);
        eff.push(hand_effort()[k]);
    }
    json!({"op": "publish", "topic": "/joint_states", "msg": {
        "header": {"seq": 1, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""},
        "name": names, "position": pos, "velocity": [], "effort": eff}})
}

fn tactile() -> Value {
    json!({"op": "publish", "topic": "/lh/tactile", "msg": {
        "header": {"seq": 1, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""},
        "pressure": [310, 320, 330, 340, 350], "temperature": [0, 0, 0, 0, 0]}})
}

struct Peer {
    url: String,
    received: Arc<Mutex<Vec<Value>>>,
    handle: Option<JoinHandle<()>>,
}

impl Peer {
    /// Waits for the peer thread to end (the client went away or it closed).
    fn join(&mut self) {
        if let Some(h) = self.handle.take() {
            h.join().unwrap();
        }
    }
}

fn peer(script: Script) -> Peer {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let url = format!("ws://{}", listener.local_addr().unwrap());
    let received = Arc::new(Mutex::new(Vec::new()));
    let rec = Arc::clone(&received);
    let handle = std::thread::spawn(move || {
        let (stream, _) = listener.accept().unwrap();
        let mut ws = tungstenite::accept(stream).unwrap();
        ws.get_mut()
            .set_read_timeout(Some(Duration::from_millis(5)))
            .unwrap();
        let mut subscribed_at: Option<Instant> = None;
        let mut last_pub = Instant::now() - Duration::from_secs(1);
        loop {
            match ws.read() {
                Ok(Message::Text(t)) => {
                    let v: Value = serde_json::from_str(t.as_str()).unwrap();
                    if v["op"] == "subscribe" && v["topic"] == "/lh/tactile" {
                        subscribed_at = Some(Instant::now());
                    }
                    rec.lock().unwrap().push(v);
                }
                Ok(Message::Close(_)) => {
                    // Answer the close handshake.
                    let _ = ws.flush();
                    return;
                }
                Ok(_) => {}
                Err(tungstenite::Error::Io(e))
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) => {}
                Err(_) => return,
            }
            let Some(t0) = subscribed_at else { continue };
            let age = t0.elapsed().as_secs_f64();
            let publish = match script {
                Script::Publish => true,
                Script::Silent => false,
                Script::PublishThenSilent(d) => age < d,
                Script::PublishThenClose(d) => {
                    if age >= d {
                        let _ = ws.close(None);
                        let _ = ws.flush();
                        return;
                    }
                    true
                }
                Script::Malformed => {
                    if last_pub.elapsed() > Duration::from_millis(10) {
                        let mut js = joint_states();
                        js["msg"]["position"][7] = json!("oops");
                        let _ = ws.send(Message::text(js.to_string()));
                        let _ = ws.send(Message::text(tactile().to_string()));
                        last_pub = Instant::now();
                    }
                    false
                }
            };
            if publish && last_pub.elapsed() > Duration::from_millis(10) {
                // A failed send means the client went away: stop publishing but keep
                // reading what it sent before, until the read side fails too.
                if ws.send(Message::text(joint_states().to_string())).is_err()
                    || ws.send(Message::text(tactile().to_string())).is_err()
                {
                    subscribed_at = None;
                    continue;
                }
                last_pub = Instant::now();
            }
        }
    });
    Peer {
        url,
        received,
        handle: Some(handle),
    }
}

fn cfg() -> RosConfig {
    RosConfig {
        timeout_s: 2.0,
        arm_motion_time_s: 0.05,
        ..RosConfig::default()
    }
}

fn published(p: &Peer, topic: &str) -> Vec<Value> {
    p.received
        .lock()
        .unwrap()
        .iter()
        .filter(|v| v["op"] == "publish" && v["topic"] == topic)
        .map(|v| v["msg"].clone())
        .collect()
}

fn positions(msg: &Value) -> Vec<f64> {
    msg["points"][0]["positions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn reads_map_names_and_commands_publish_trajectories() {
    let mut p = peer(Script::Publish);
    let mut arm = RosHandArm::connect(&p.url, cfg()).unwrap();
    let r = arm.read().unwrap();
    assert_close(&r.joint_angles, &hand_q());
    assert_eq!(r.tactile_raw, [310.0, 320.0, 330.0, 340.0, 350.0]);
    // Actuators: WRJ2, WRJ1, FFJ4, FFJ3, FFJ0 = FFJ2 + FFJ1 (40 + 50), ...
    assert_eq!(&r.tendon_raw[..5], &[0.0, 10.0, 20.0, 30.0, 90.0]);
    assert_eq!(r.tendon_raw[19], 230.0);
    assert_close(&arm.arm_joints().unwrap(), &ARM_Q);
    // The subscriptions and advertisements went out first.
    let ops: Vec<(String, String)> = p.received.lock().unwrap()[..4]
        .iter()
        .map(|v| {
            (
                v["op"].as_str().unwrap().into(),
                v["topic"].as_str().unwrap().into(),
            )
        })
        .collect();
    assert_eq!(
        ops,
        vec![
            ("subscribe".into(), "/joint_states".into()),
            ("subscribe".into(), "/lh/tactile".into()),
            (
                "advertise".into(),
                "/lh_trajectory_controller/command".into()
            ),
            (
                "advertise".into(),
                "/la_trajectory_controller/command".into()
            ),
        ]
    );
    // Hand command.
    let t: [f64; 24] = std::array::from_fn(|k| 0.02 * k as f64);
    arm.command_hand(&t).unwrap();
    // Arm joints, then a lift of 10 cm computed from the measured arm joints.
    let q = [0.1, -1.1, 1.5, -1.9, -1.5, 0.2];
    arm.move_arm(&ArmMotion::Joints(q)).unwrap();
    arm.move_arm(&ArmMotion::Lift {
        height_m: 0.1,
        duration_s: 0.05,
    })
    .unwrap();
    arm.stop().unwrap();
    let mut nan = t;
    nan[4] = f64::NAN;
    assert!(matches!(
        arm.command_hand(&nan),
        Err(HwError::InvalidCommand { .. })
    ));
    drop(arm);
    p.join();
    let hand = published(&p, "/lh_trajectory_controller/command");
    assert_eq!(hand.len(), 2, "command and stop");
    assert_eq!(hand[0]["joint_names"][3], "lh_FFJ3");
    assert_close(&positions(&hand[0]), &t);
    assert_eq!(
        hand[0]["points"][0]["time_from_start"],
        json!({"secs": 0, "nsecs": 100_000_000})
    );
    // stop holds the measured hand angles.
    assert_close(&positions(&hand[1]), &hand_q());
    let arm_msgs = published(&p, "/la_trajectory_controller/command");
    assert_eq!(arm_msgs.len(), 3, "joints, lift, stop");
    assert_eq!(arm_msgs[0]["joint_names"][0], "la_shoulder_pan_joint");
    assert_close(&positions(&arm_msgs[0]), &q);
    let lifted: [f64; 6] = positions(&arm_msgs[1]).try_into().unwrap();
    let dz = ur10e::fk(&lifted).translation.z - ur10e::fk(&ARM_Q).translation.z;
    assert!((dz - 0.1).abs() < 1e-6, "{dz}");
}

#[test]
fn no_data_is_a_timeout() {
    let mut p = peer(Script::Silent);
    let short = RosConfig {
        timeout_s: 0.3,
        ..cfg()
    };
    let mut arm = RosHandArm::connect(&p.url, short).unwrap();
    let t = Instant::now();
    let e = arm.read().unwrap_err();
    let waited = t.elapsed().as_secs_f64();
    assert!(matches!(e, HwError::Timeout { .. }), "{e}");
    assert!(e.to_string().contains("/joint_states"), "{e}");
    assert!((0.3..3.0).contains(&waited), "{waited}");
    drop(arm);
    p.join();
}

#[test]
fn stale_data_trips_the_watchdog_which_stops_the_robot() {
    let mut p = peer(Script::PublishThenSilent(0.3));
    let arm = RosHandArm::connect(&p.url, cfg()).unwrap();
    let mut safe = SafeHandArm::new(
        arm,
        Robot::builtin(Side::Left).hand_limits(),
        SafetyConfig::default(),
        Arc::new(AtomicBool::new(false)),
    )
    .unwrap();
    let start = Instant::now();
    let err = loop {
        if let Err(e) = safe.read().and_then(|_| safe.wait(0.02)) {
            break e;
        }
        assert!(start.elapsed() < Duration::from_secs(5), "never stopped");
    };
    assert!(matches!(err, HwError::Timeout { .. }), "{err}");
    assert_eq!(safe.stop_count(), 1);
    drop(safe);
    p.join();
    // The stop published hold commands.
    // The stop published a hold command.
    assert_eq!(published(&p, "/lh_trajectory_controller/command").len(), 1);
}

#[test]
fn a_closed_connection_is_a_disconnect() {
    let mut p = peer(Script::PublishThenClose(0.1));
    let mut arm = RosHandArm::connect(&p.url, cfg()).unwrap();
    let start = Instant::now();
    let err = loop {
        match arm.read().and_then(|_| arm.wait(0.02)) {
            Ok(()) => assert!(start.elapsed() < Duration::from_secs(5)),
            Err(e) => break e,
        }
    };
    assert!(matches!(err, HwError::Disconnected(_)), "{err}");
    p.join();
    // Nobody listening: connecting fails with a clear error.
    let e = RosHandArm::connect(&p.url, cfg())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("cannot connect"), "{e}");
}

#[test]
fn malformed_messages_and_urls_are_named() {
    let mut p = peer(Script::Malformed);
    let mut arm = RosHandArm::connect(&p.url, cfg()).unwrap();
    let e = arm.read().unwrap_err().to_string();
    assert!(e.contains("/joint_states.position[7]"), "{e}");
    drop(arm);
    p.join();
    let e = RosHandArm::connect("wss://example.invalid:9090", cfg())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("only ws://"), "{e}");
}

/// The rosbridge message decoder never panics on junk or on mutated valid messages (a
/// byte changed, inserted, removed or the message cut), and still decodes the valid ones.
/// `PROPTEST_CASES` sets the cases per property (default 3000).
#[test]
fn decoder_survives_fuzzed_messages() {
    use grasp::hardware::ros::RosDecoder;
    use proptest::prelude::*;
    use proptest::test_runner::{Config, TestRunner};
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3000);
    let seeds = [joint_states().to_string(), tactile().to_string()];
    let mut dec = RosDecoder::new(RosConfig::default());
    for s in &seeds {
        dec.handle(s, 1.0).unwrap();
    }
    assert!(dec.hand_q().is_some() && dec.tactile().is_some() && dec.arm_q().is_some());
    let edit = (0usize..4, any::<usize>(), any::<u8>());
    let strategy = (0usize..2, prop::collection::vec(edit, 1..8));
    let mut runner = TestRunner::new(Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    });
    runner
        .run(&strategy, |(which, edits)| {
            let mut b = seeds[which].clone().into_bytes();
            for (op, pos, byte) in edits {
                let n = b.len().max(1);
                match op {
                    0 if !b.is_empty() => b[pos % n] = byte,
                    1 => b.insert(pos % (b.len() + 1), byte),
                    2 if !b.is_empty() => {
                        b.remove(pos % n);
                    }
                    _ => b.truncate(pos % (b.len() + 1)),
                }
            }
            let mut d = RosDecoder::new(RosConfig::default());
            if let Err(e) = d.handle(&String::from_utf8_lossy(&b), 2.0) {
                prop_assert!(!e.to_string().is_empty());
            }
            Ok(())
        })
        .unwrap();
    let mut runner = TestRunner::new(Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    });
    runner
        .run(&".{0,200}", |text| {
            let _ = RosDecoder::new(RosConfig::default()).handle(&text, 0.0);
            Ok(())
        })
        .unwrap();
}
