//! Fuzz target: arbitrary bytes, split into arbitrary chunks, through the streaming decoder.
//! Checks that it never panics, that every byte is counted, that chunking does not change the
//! result, and that every frame it returns re-encodes to a valid frame.
#![no_main]

use crackbot_protocol::{Decoder, Frame};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // First byte picks the chunk size, the rest is the stream.
    let Some((&chunk, bytes)) = data.split_first() else { return };
    let chunk = usize::from(chunk).max(1);

    let mut whole = Vec::new();
    let mut d = Decoder::new();
    d.feed(bytes, |r| whole.push(r));
    let stats = *d.stats();
    assert_eq!(stats.bytes, bytes.len() as u64);
    assert_eq!(stats.frames + stats.resyncs(), whole.len() as u64);

    let mut pieces = Vec::new();
    let mut d = Decoder::new();
    for c in bytes.chunks(chunk) {
        d.feed(c, |r| pieces.push(r));
    }
    assert_eq!(whole, pieces);

    for frame in whole.iter().flatten() {
        let again = Frame::from_payload(&frame.to_payload());
        assert_eq!(again, Ok(*frame));
    }
});
