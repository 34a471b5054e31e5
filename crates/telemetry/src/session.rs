//! Opening a Zenoh session: peer mode on loopback by default, a router address for sites.

use zenoh::Wait;

use crate::TelemetryError;

/// Where the station listens by default, and where robots connect by default: one station on
/// this machine sees every robot on it with no flag.
pub const DEFAULT_STATION_ENDPOINT: &str = "tcp/127.0.0.1:7447";

/// How a node joins the Zenoh network.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct ZenohOptions {
    /// Endpoints this node listens on (e.g. `tcp/127.0.0.1:7448`).
    pub listen: Vec<String>,
    /// Endpoints this node connects to, retrying in the background until they answer.
    pub connect: Vec<String>,
    /// A site's Zenoh router: the node becomes its client (`listen` and `connect` ignored).
    pub router: Option<String>,
    /// Multicast scouting (off by default: explicit endpoints are predictable, and many
    /// networks drop multicast).
    pub multicast_scouting: bool,
}

impl ZenohOptions {
    /// The Zenoh configuration.
    pub fn config(&self) -> Result<zenoh::Config, TelemetryError> {
        let mut c = zenoh::Config::default();
        let set = |c: &mut zenoh::Config, key: &str, value: String| {
            c.insert_json5(key, &value)
                .map_err(|e| TelemetryError::Config(format!("{key} = {value}: {e}")))
        };
        let list = |v: &[String]| serde_json::to_string(v).unwrap_or_else(|_| "[]".to_string());
        for e in self.listen.iter().chain(&self.connect).chain(&self.router) {
            check_endpoint(e)?;
        }
        match &self.router {
            Some(r) => {
                set(&mut c, "mode", "\"client\"".into())?;
                set(&mut c, "connect/endpoints", list(std::slice::from_ref(r)))?;
            }
            None => {
                set(&mut c, "mode", "\"peer\"".into())?;
                set(&mut c, "listen/endpoints", list(&self.listen))?;
                set(&mut c, "connect/endpoints", list(&self.connect))?;
                // Keep retrying endpoints that are not up yet (a station started after its
                // robots, a robot restarted): once a second at most.
                set(&mut c, "connect/timeout_ms", "-1".into())?;
                set(&mut c, "connect/exit_on_failure", "false".into())?;
                set(
                    &mut c,
                    "connect/retry",
                    "{period_init_ms: 250, period_max_ms: 1000, period_increase_factor: 2}".into(),
                )?;
            }
        }
        set(
            &mut c,
            "scouting/multicast/enabled",
            self.multicast_scouting.to_string(),
        )?;
        Ok(c)
    }

    /// Opens the session.
    pub fn open(&self) -> Result<zenoh::Session, TelemetryError> {
        let config = self.config()?;
        zenoh::open(config)
            .wait()
            .map_err(|e| TelemetryError::Open(e.to_string()))
    }
}

/// An endpoint looks like `proto/address:port` (`tcp/127.0.0.1:7447`, `udp/[::1]:7447`).
fn check_endpoint(e: &str) -> Result<(), TelemetryError> {
    let ok = e
        .split_once('/')
        .is_some_and(|(proto, addr)| !proto.is_empty() && addr.contains(':'));
    if ok {
        Ok(())
    } else {
        Err(TelemetryError::Config(format!(
            "endpoint {e:?} is not of the form tcp/HOST:PORT"
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_option_makes_a_valid_zenoh_configuration() {
        let peer = ZenohOptions {
            listen: vec!["tcp/127.0.0.1:7448".into()],
            connect: vec![DEFAULT_STATION_ENDPOINT.into()],
            ..ZenohOptions::default()
        };
        assert!(peer.config().is_ok());
        let client = ZenohOptions {
            router: Some("tcp/10.0.0.1:7447".into()),
            ..ZenohOptions::default()
        };
        assert!(client.config().is_ok());
        let bad = ZenohOptions {
            connect: vec!["127.0.0.1:7447".into()],
            ..ZenohOptions::default()
        };
        let e = bad.config().unwrap_err().to_string();
        assert!(
            e.contains("127.0.0.1:7447") && e.contains("tcp/HOST:PORT"),
            "{e}"
        );
    }
}
