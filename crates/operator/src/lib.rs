//! The operator's desktop app.
