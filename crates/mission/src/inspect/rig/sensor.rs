//! The sensor stream on the host's clock.

use std::time::Instant;

use crackbot_acquisition::{PortConfig, SensorStream, TryNext};

use crate::sync::ClockSync;
use crate::MissionError;

/// One sensor sample on the host's clock.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TimedSample {
    pub(crate) device_us: f64,
    pub(crate) host_us: f64,
    pub(crate) raw: [u16; 4],
}

pub(crate) struct Sensor {
    pub(crate) stream: SensorStream,
    pub(crate) sync: ClockSync,
    pub(crate) offset_us: f64,
    pub(crate) samples: Vec<TimedSample>,
    pub(crate) last_at: Instant,
    pub(crate) path: String,
}

impl Sensor {
    pub(crate) fn open(path: &str, t0: Instant) -> Result<Sensor, MissionError> {
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
    pub(crate) fn drain(&mut self) -> Result<usize, MissionError> {
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
