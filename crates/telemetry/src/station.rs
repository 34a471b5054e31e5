//! The station's side: watches every robot it can reach and sends them signed commands.

use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use crackbot_link::Key;
use zenoh::query::ConsolidationMode;
use zenoh::sample::SampleKind;
use zenoh::Wait;

use crate::command::{Command, CommandReply, CommandSigner};
use crate::fleet::Fleet;
use crate::keys::{self, ROOT};
use crate::wire;
use crate::{TelemetryError, ZenohOptions};

/// A station on the Zenoh network: a [`Fleet`] kept up to date from every robot's samples and
/// liveliness tokens.
pub struct Station {
    session: zenoh::Session,
    fleet: Arc<Mutex<Fleet>>,
    signer: Mutex<CommandSigner>,
    _samples: zenoh::pubsub::Subscriber<()>,
    _alive: zenoh::pubsub::Subscriber<()>,
}

impl std::fmt::Debug for Station {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Station").finish_non_exhaustive()
    }
}

impl Station {
    /// Joins the network; `key` signs commands (`None`: this station can watch, and send
    /// emergency stops, but robots refuse its other commands).
    pub fn open(options: &ZenohOptions, key: Option<&Key>) -> Result<Self, TelemetryError> {
        let session = options.open()?;
        let fleet = Arc::new(Mutex::new(Fleet::new()));
        let declare = |what: &str, e: zenoh::Error| TelemetryError::Declare {
            what: what.to_string(),
            detail: e.to_string(),
        };
        let samples = {
            let fleet = fleet.clone();
            session
                .declare_subscriber(format!("{ROOT}/*/*"))
                .callback(move |sample| {
                    let key = sample.key_expr().as_str().to_string();
                    let bytes = sample.payload().to_bytes();
                    apply(&fleet, &key, &bytes);
                })
                .wait()
                .map_err(|e| declare("the telemetry subscriber", e))?
        };
        let alive = {
            let fleet = fleet.clone();
            let weak = session.clone();
            session
                .liveliness()
                .declare_subscriber(format!("{ROOT}/*/alive"))
                .history(true)
                .callback(move |sample| {
                    let Some(robot) = keys::robot_of(sample.key_expr().as_str()) else {
                        return;
                    };
                    let up = sample.kind() == SampleKind::Put;
                    lock(&fleet).set_alive(robot, up);
                    if !up {
                        tracing::warn!("robot {robot} lost (its liveliness token went away)");
                        return;
                    }
                    // A robot appeared (this station just joined, or it did): catch up with
                    // its state, without blocking Zenoh's thread.
                    let fleet = fleet.clone();
                    let asked = weak
                        .get(keys::state_key(robot))
                        // Every reply: they share one key, which consolidation would reduce
                        // to the last.
                        .consolidation(ConsolidationMode::None)
                        .timeout(Duration::from_secs(5))
                        .callback(move |reply| {
                            if let Ok(sample) = reply.result() {
                                apply(
                                    &fleet,
                                    sample.key_expr().as_str(),
                                    &sample.payload().to_bytes(),
                                );
                            }
                        })
                        .wait();
                    if let Err(e) = asked {
                        tracing::warn!("asking robot {robot} for its state: {e}");
                    }
                })
                .wait()
                .map_err(|e| declare("the liveliness subscriber", e))?
        };
        let station = Station {
            session,
            fleet,
            signer: Mutex::new(CommandSigner::new(key)),
            _samples: samples,
            _alive: alive,
        };
        Ok(station)
    }

    /// Asks every reachable robot for its current state (the latest of each topic and the
    /// mission's verdicts so far), waiting up to `timeout` for the answers. The station does
    /// this by itself for each robot whose liveliness token appears (when it joins, and when a
    /// robot starts); this call waits for it.
    pub fn catch_up(&self, timeout: Duration) -> Result<usize, TelemetryError> {
        let replies = self
            .session
            .get(format!("{ROOT}/*/state"))
            .consolidation(ConsolidationMode::None)
            .timeout(timeout)
            .wait()
            .map_err(|e| TelemetryError::Query {
                key: format!("{ROOT}/*/state"),
                detail: e.to_string(),
            })?;
        let mut n = 0;
        while let Ok(reply) = replies.recv() {
            if let Ok(sample) = reply.result() {
                apply(
                    &self.fleet,
                    sample.key_expr().as_str(),
                    &sample.payload().to_bytes(),
                );
                n += 1;
            }
        }
        Ok(n)
    }

    /// The fleet as it stands (hold the guard briefly: samples wait for it).
    pub fn fleet(&self) -> MutexGuard<'_, Fleet> {
        lock(&self.fleet)
    }

    /// A shared handle on the fleet, for a UI thread.
    pub fn fleet_handle(&self) -> Arc<Mutex<Fleet>> {
        self.fleet.clone()
    }

    /// Whether this station signs its commands.
    pub fn has_key(&self) -> bool {
        lock(&self.signer).has_key()
    }

    /// Sends `command` to `robot` and waits up to `timeout` for its answer.
    pub fn command(
        &self,
        robot: &str,
        command: Command,
        timeout: Duration,
    ) -> Result<CommandReply, TelemetryError> {
        keys::check_robot_name(robot).map_err(TelemetryError::Config)?;
        let payload = lock(&self.signer).encode(robot, command);
        self.send_raw(robot, payload, timeout)
    }

    /// Sends a command payload as it is (tests replay recorded ones with this).
    pub fn send_raw(
        &self,
        robot: &str,
        payload: Vec<u8>,
        timeout: Duration,
    ) -> Result<CommandReply, TelemetryError> {
        let key = keys::command_key(robot);
        let replies = self
            .session
            .get(&key)
            .payload(payload)
            .timeout(timeout)
            .wait()
            .map_err(|e| TelemetryError::Query {
                key: key.clone(),
                detail: e.to_string(),
            })?;
        let started = Instant::now();
        while let Ok(reply) = replies.recv() {
            if let Ok(sample) = reply.result() {
                return postcard::from_bytes(&sample.payload().to_bytes()).map_err(|e| {
                    TelemetryError::Query {
                        key: key.clone(),
                        detail: format!("malformed reply: {e}"),
                    }
                });
            }
        }
        Err(TelemetryError::NoAnswer {
            robot: robot.to_string(),
            waited_s: started.elapsed().as_secs_f64(),
        })
    }

    /// Signs a command without sending it (tests record one to replay it).
    pub fn sign(&self, robot: &str, command: Command) -> Vec<u8> {
        lock(&self.signer).encode(robot, command)
    }
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

fn apply(fleet: &Mutex<Fleet>, key: &str, bytes: &[u8]) {
    let Some(robot) = keys::robot_of(key) else {
        return;
    };
    match wire::decode(bytes) {
        Ok(env) if env.robot == robot => lock(fleet).apply(env, Instant::now()),
        Ok(env) => {
            tracing::warn!("sample on {key} claims robot {:?}: dropped", env.robot);
            lock(fleet).count_undecodable(robot);
        }
        Err(e) => {
            tracing::warn!("sample on {key}: {e}");
            lock(fleet).count_undecodable(robot);
        }
    }
}
