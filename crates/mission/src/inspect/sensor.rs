//! The sensor stream on the host's clock.

use std::time::Instant;

use crackbot_acquisition::{PortConfig, SensorStream, TryNext};

use crate::sync::ClockSync;
use crate::MissionError;

/// One sensor sample on the host's clock.
#[derive(Debug, Clone, Copy)]
pub(super) struct TimedSample {
    pub(super) device_us: f64,
    pub(super) host_us: f64,
    pub(super) raw: [u16; 4],
}

pub(super) struct Sensor {
    pub(super) stream: SensorStream,
    pub(super) sync: ClockSync,
    pub(super) offset_us: f64,
    pub(super) samples: Vec<TimedSample>,
    pub(super) last_at: Instant,
    pub(super) path: String,
}

impl Sensor {
    pub(super) fn open(path: &str, t0: Instant) -> Result<Sensor, MissionError> {
        let stream = SensorStream::open(&PortConfig::new(path))?;
        let offset_us = stream
            .opened_at()
            .saturating_duration_since(t0)
            .as_secs_f64()
            * 1e6;
        Ok(Sensor {
            stream,
            sync: ClockSync::new(30e6),
            offset_us,
            samples: Vec::new(),
            last_at: Instant::now(),
            path: path.to_string(),
        })
    }

    /// Takes what has arrived.
    pub(super) fn drain(&mut self) -> Result<usize, MissionError> {
        let mut n = 0;
        loop {
            match self.stream.try_next() {
                TryNext::Ready(Ok(s)) => {
                    let host = self.offset_us + s.host_time.as_secs_f64() * 1e6;
                    self.sync.add(s.device_time_us as f64, host);
                    self.samples.push(TimedSample {
                        device_us: s.device_time_us as f64,
                        host_us: host,
                        raw: s.raw,
                    });
                    self.last_at = Instant::now();
                    n += 1;
                }
                TryNext::Ready(Err(e)) => return Err(e.into()),
                TryNext::Empty => return Ok(n),
                TryNext::Ended => {
                    return Err(MissionError::SensorLost {
                        port: self.path.clone(),
                    })
                }
            }
        }
    }
}
