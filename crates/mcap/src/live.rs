//! The live view (cargo feature `live`): the log's channels over the Foxglove WebSocket
//! protocol, for the Foxglove app to watch a mission as it runs.

use std::net::SocketAddr;

use foxglove::WebSocketServer;

use crate::writer::LogWriter;
use crate::LogError;

/// Where the live server listens unless told otherwise: loopback, Foxglove's usual port.
pub const DEFAULT_LIVE_ADDR: &str = "127.0.0.1:8765";

impl LogWriter {
    /// Serves every channel of this log on `addr` (port 0: any free one) from now until
    /// [`LogWriter::finish`]; returns the address it listens on. A client that connects later
    /// sees the messages logged from then on.
    pub fn serve(&mut self, addr: SocketAddr) -> Result<SocketAddr, LogError> {
        let refused = |detail: String| LogError::Serve {
            addr: addr.to_string(),
            detail,
        };
        let server = WebSocketServer::new()
            .name("crackbot")
            .context(self.context())
            .bind(addr.ip().to_string(), addr.port());
        // The SDK's blocking start runs its own runtime and must not be called from inside an
        // async one (the robot's binaries run missions from one): start it from a thread.
        let handle = std::thread::spawn(move || server.start_blocking())
            .join()
            .map_err(|_| refused("the server's start panicked".into()))?
            .map_err(|e| refused(e.to_string()))?;
        let local = SocketAddr::new(addr.ip(), handle.port());
        self.server = Some(handle);
        Ok(local)
    }
}
