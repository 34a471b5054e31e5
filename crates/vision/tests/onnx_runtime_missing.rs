//! A missing or wrong ONNX Runtime library is a clear error naming the version and the fix, never a
//! panic. One test per file: the runtime is loaded once per process.

#![cfg(feature = "onnx")]

use crackbot_vision::onnx::OnnxDetector;
use crackbot_vision::preprocess::PostprocessParams;

#[test]
fn wrong_or_missing_runtime_names_the_version_and_the_fix() {
    let model = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/detector/crack-detector-320.onnx"
    );
    // Not a file.
    std::env::set_var("ORT_DYLIB_PATH", "/nonexistent/libonnxruntime.so.1.31.1");
    let err = OnnxDetector::load(model.as_ref(), PostprocessParams::default(), 1)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("not a file") && err.contains("1.31.1") && err.contains("setup.sh"),
        "{err}"
    );
    // A shared library that is not ONNX Runtime (the runtime is loaded once per process, so this
    // is the only load attempted here).
    let not_ort = [
        "/lib/x86_64-linux-gnu/libz.so.1",
        "/usr/lib/x86_64-linux-gnu/libz.so.1",
    ]
    .into_iter()
    .find(|p| std::path::Path::new(p).is_file())
    .expect("zlib is on every Debian machine");
    std::env::set_var("ORT_DYLIB_PATH", not_ort);
    let err = OnnxDetector::load(model.as_ref(), PostprocessParams::default(), 1)
        .unwrap_err()
        .to_string();
    assert!(err.contains("1.31.1") && err.contains("libz"), "{err}");
    // The failure is remembered, not retried into a panic.
    let again = OnnxDetector::load(model.as_ref(), PostprocessParams::default(), 1)
        .unwrap_err()
        .to_string();
    assert_eq!(again, err);
}
