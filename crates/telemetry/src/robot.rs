//! The robot's side: publishes what its missions see, feel and decide, answers state queries
//! (so a station that joins mid-mission catches up) and signed commands.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crackbot_link::Key;
use zenoh::qos::{CongestionControl, Priority};
use zenoh::Wait;

use crate::command::{unix_ms, Command, CommandGuard, CommandReply};
use crate::keys::{self, Topic};
use crate::wire::{self, Envelope, Health, StreamHealth, Telemetry, WIRE_VERSION};
use crate::{TelemetryError, ZenohOptions};

/// How often the heartbeat goes out.
pub const HEARTBEAT_EVERY: Duration = Duration::from_millis(200);

/// What the robot does with a command that passed the checks: `Ok` to accept it, `Err(reason)`
/// to refuse it (e.g. "a mission is already running"). Called on a Zenoh thread: keep it short.
pub type CommandHandler = Box<dyn Fn(&Command) -> Result<(), String> + Send + Sync>;

struct Shared {
    robot: String,
    session: zenoh::Session,
    seq: AtomicU64,
    /// The latest sample of each topic but `tactile`; every verdict of the mission.
    latest: Mutex<Latest>,
    stream: Mutex<Option<StreamHealth>>,
    started: Instant,
    closed: AtomicBool,
}

#[derive(Default)]
struct Latest {
    by_topic: BTreeMap<Topic, Envelope>,
    verdicts: Vec<Envelope>,
}

/// A robot on the Zenoh network (see the crate docs for its keys). Dropping it withdraws its
/// liveliness token: stations show it as lost.
pub struct RobotNode {
    shared: Arc<Shared>,
    _token: zenoh::liveliness::LivelinessToken,
    _state: zenoh::query::Queryable<()>,
    _commands: zenoh::query::Queryable<()>,
    heartbeat: Option<std::thread::JoinHandle<()>>,
}

impl std::fmt::Debug for RobotNode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RobotNode")
            .field("robot", &self.shared.robot)
            .finish()
    }
}

impl RobotNode {
    /// Joins the network as `robot`; commands that pass [`CommandGuard`] (with `key`; `None`:
    /// only emergency stops) go to `on_command`.
    pub fn open(
        robot: &str,
        options: &ZenohOptions,
        key: Option<&Key>,
        on_command: CommandHandler,
    ) -> Result<Self, TelemetryError> {
        keys::check_robot_name(robot).map_err(TelemetryError::Config)?;
        let session = options.open()?;
        let shared = Arc::new(Shared {
            robot: robot.to_string(),
            session: session.clone(),
            seq: AtomicU64::new(0),
            latest: Mutex::new(Latest::default()),
            stream: Mutex::new(None),
            started: Instant::now(),
            closed: AtomicBool::new(false),
        });
        let declare = |what: &str, e: zenoh::Error| TelemetryError::Declare {
            what: what.to_string(),
            detail: e.to_string(),
        };
        let token = session
            .liveliness()
            .declare_token(keys::alive_key(robot))
            .wait()
            .map_err(|e| declare("the liveliness token", e))?;
        let state = {
            let shared = shared.clone();
            // Replies name this robot's key, not the query's (which may be `crackbot/*/state`).
            let key = keys::state_key(robot);
            session
                .declare_queryable(keys::state_key(robot))
                .callback(move |query| {
                    for env in shared.snapshot() {
                        if let Ok(bytes) = wire::encode(&env) {
                            let _ = query.reply(key.clone(), bytes).wait();
                        }
                    }
                })
                .wait()
                .map_err(|e| declare("the state queryable", e))?
        };
        let guard = Mutex::new(CommandGuard::new(robot, key));
        let command_key = keys::command_key(robot);
        let commands = session
            .declare_queryable(keys::command_key(robot))
            .callback(move |query| {
                let payload = query
                    .payload()
                    .map(|p| p.to_bytes().to_vec())
                    .unwrap_or_default();
                let checked = guard
                    .lock()
                    .unwrap_or_else(std::sync::PoisonError::into_inner)
                    .check(&payload, unix_ms());
                let reply = match checked {
                    Ok(command) => match on_command(&command) {
                        Ok(()) => {
                            tracing::info!("command {} accepted", command.name());
                            CommandReply::Accepted
                        }
                        Err(reason) => CommandReply::Refused(reason),
                    },
                    Err(refusal) => {
                        tracing::warn!("command refused: {refusal}");
                        CommandReply::Refused(refusal.to_string())
                    }
                };
                let bytes = postcard::to_allocvec(&reply).unwrap_or_default();
                let _ = query.reply(command_key.clone(), bytes).wait();
            })
            .wait()
            .map_err(|e| declare("the command queryable", e))?;
        let heartbeat = {
            let shared = shared.clone();
            std::thread::Builder::new()
                .name(format!("telemetry-{robot}"))
                .spawn(move || {
                    while !shared.closed.load(Ordering::Relaxed) {
                        let stream = *shared
                            .stream
                            .lock()
                            .unwrap_or_else(std::sync::PoisonError::into_inner);
                        let h = Telemetry::Health(Health {
                            uptime_s: shared.started.elapsed().as_secs_f64(),
                            stream,
                        });
                        if let Err(e) = shared.publish(h) {
                            tracing::warn!("heartbeat: {e}");
                        }
                        std::thread::sleep(HEARTBEAT_EVERY);
                    }
                })
                .map_err(|e| TelemetryError::Open(format!("heartbeat thread: {e}")))?
        };
        Ok(RobotNode {
            shared,
            _token: token,
            _state: state,
            _commands: commands,
            heartbeat: Some(heartbeat),
        })
    }

    /// The robot's name.
    pub fn name(&self) -> &str {
        &self.shared.robot
    }

    /// Publishes one sample (and keeps it for the state query).
    pub fn publish(&self, body: Telemetry) -> Result<(), TelemetryError> {
        self.shared.publish(body)
    }

    /// The stream counters the next heartbeats carry (`None`: no mission running).
    pub fn set_stream_health(&self, h: Option<StreamHealth>) {
        *self
            .shared
            .stream
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner) = h;
    }

    /// Publishes what a mission's progress event carries (see [`wire::from_progress`]); the
    /// stream's health goes into the heartbeat.
    pub fn publish_progress(
        &self,
        p: &crackbot_mission::inspect::Progress,
    ) -> Result<(), TelemetryError> {
        if let crackbot_mission::inspect::Progress::Health(h) = p {
            self.set_stream_health(Some(StreamHealth::from(h)));
        }
        match wire::from_progress(p)? {
            Some(body) => self.publish(body),
            None => Ok(()),
        }
    }
}

impl Shared {
    fn publish(&self, body: Telemetry) -> Result<(), TelemetryError> {
        let topic = body.topic();
        let env = Envelope {
            version: WIRE_VERSION,
            robot: self.robot.clone(),
            seq: self.seq.fetch_add(1, Ordering::Relaxed) + 1,
            sent_unix_ms: unix_ms(),
            body,
        };
        let bytes = wire::encode(&env)?;
        {
            let mut latest = self
                .latest
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            match topic {
                Topic::Tactile => {}
                // A running verdict is stale once its pass is judged: not kept for catch-up.
                Topic::Verdicts if matches!(env.body, Telemetry::Feeling(_)) => {}
                Topic::Verdicts => latest.verdicts.push(env),
                Topic::Mission => {
                    let new = latest.by_topic.get(&Topic::Mission).is_none_or(|old| {
                        !matches!((&old.body, &env.body), (Telemetry::Mission(a), Telemetry::Mission(b)) if a.mission == b.mission)
                    });
                    if new {
                        // A new mission: forget the last one's frame, candidates, plan, verdicts.
                        latest.verdicts.clear();
                        for t in [Topic::Camera, Topic::Detections, Topic::Plan] {
                            latest.by_topic.remove(&t);
                        }
                    }
                    latest.by_topic.insert(topic, env);
                }
                _ => {
                    latest.by_topic.insert(topic, env);
                }
            }
        }
        // The state a station shows (mission, frame, candidates, plan, verdicts) is sent once:
        // it waits for a full queue rather than being dropped, and goes ahead of the 400 Hz
        // samples and heartbeats, which the next ones replace.
        let (congestion, priority) = match topic {
            Topic::Tactile | Topic::Health => (CongestionControl::Drop, Priority::DataLow),
            _ => (CongestionControl::Block, Priority::Data),
        };
        self.session
            .put(keys::topic_key(&self.robot, topic), bytes)
            .congestion_control(congestion)
            .priority(priority)
            .wait()
            .map_err(|e| TelemetryError::Publish {
                key: keys::topic_key(&self.robot, topic),
                detail: e.to_string(),
            })
    }

    /// The state a joining station needs: the mission first, then the rest, verdicts last.
    fn snapshot(&self) -> Vec<Envelope> {
        let latest = self
            .latest
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let mut out: Vec<Envelope> = latest
            .by_topic
            .get(&Topic::Mission)
            .cloned()
            .into_iter()
            .collect();
        out.extend(
            latest
                .by_topic
                .iter()
                .filter(|(t, _)| **t != Topic::Mission)
                .map(|(_, e)| e.clone()),
        );
        out.extend(latest.verdicts.iter().cloned());
        out
    }
}

impl Drop for RobotNode {
    fn drop(&mut self) {
        self.shared.closed.store(true, Ordering::Relaxed);
        if let Some(h) = self.heartbeat.take() {
            let _ = h.join();
        }
    }
}
