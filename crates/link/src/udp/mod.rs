//! The std side: the UDP endpoint, the key file, the epoch file and fault injection.

mod endpoint;
mod epoch;
mod fault;
mod key_file;

pub use endpoint::{EpochSource, LinkConfig, LinkEndpoint, LinkError, Received, Security};
pub use epoch::{EpochError, EpochFile};
pub use fault::{Fate, FaultConfig, FaultInjector, FaultStats, PacketInfo};
pub use key_file::KeyFileError;
