//! The workspace's layering, checked from `cargo metadata` and `cargo tree` so it cannot decay
//! unnoticed:
//!
//! * every crate sits in one layer and depends (normal or build) only on crates of lower layers;
//! * no crate depends on a binary-only crate;
//! * the `no_std` crates stay `no_std` and pull only `no_std` dependencies;
//! * the robot path (the headless `crackbot` binary and every library it uses) builds without
//!   plotters, statistics, GUI, Zenoh or WebSocket-server crates by default;
//! * plotting lives in `crackbot-plots` only; a GUI toolkit only in the operator app;
//! * libraries report errors with their own enums and progress through callbacks: no `anyhow`,
//!   `clap` or `indicatif` in a library-only crate.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::process::Command;

use serde_json::Value;

/// The layers, lowest first. A crate may depend on crates of lower layers only; a new crate must
/// be placed here (the test fails until it is).
const LAYERS: &[(&str, &[&str])] = &[
    (
        "foundations: wire formats (sensor, manipulator link), data location",
        &["crackbot-protocol", "crackbot-datasets", "crackbot-link"],
    ),
    (
        "data: firmware, recordings, image geometry and annotations, the finger's fibre",
        &[
            "crackbot-firmware",
            "crackbot-recording",
            "crackbot-imaging",
            "crackbot-fibre",
        ],
    ),
    (
        "surface: a plate's features and their heights (the simulator's and the printed plates')",
        &["crackbot-surface"],
    ),
    (
        "camera model: the lens and its calibration from a flat target's points",
        &["crackbot-calib"],
    ),
    (
        "components: sensor link, signals, classifiers, camera, the printed target, simulator, planner",
        &[
            "crackbot-acquisition",
            "crackbot-calib-target",
            "crackbot-dsp",
            "crackbot-forest",
            "crackbot-vision",
            "crackbot-sim",
            "crackbot-planner",
            "crackbot-testkit",
            "crackbot-mcap",
        ],
    ),
    (
        "pipelines: the emulated sensor, the tactile pipeline, the reference plates, the log as a ROS 2 bag",
        &["crackbot-emulator", "crackbot-tactile", "crackbot-plates", "crackbot-rosbag"],
    ),
    (
        "hardware: the manipulator controller (the simulated arm over the emulated sensor, the ROS 2 arm) and the link's conformance suite",
        &["crackbot-controller", "crackbot-conformance"],
    ),
    (
        "services: missions, figures",
        &["crackbot-mission", "crackbot-plots"],
    ),
    ("fleet: telemetry over Zenoh", &["crackbot-telemetry"]),
    (
        "research: the paper's experiments as whole missions, their scoring and tables",
        &["crackbot-research"],
    ),
    (
        "front ends: binaries, the operator app and cross-crate tests",
        &[
            "crackbot-cli",
            "crackbot-lab",
            "crackbot-operator",
            "crackbot-tests",
        ],
    ),
];

/// Crates that must stay `no_std` (the firmware runs on the microcontroller).
const NO_STD: &[&str] = &["crackbot-protocol", "crackbot-firmware", "crackbot-link"];

/// What a `no_std` crate may pull in (all `no_std` themselves).
const NO_STD_ALLOWED: &[&str] = &[
    "crackbot-protocol",
    "crackbot-firmware",
    "thiserror",
    "crc",
    "crc-catalog",
    "cobs",
    "memchr",
    "heapless",
    "hash32",
    "byteorder",
    "stable_deref_trait",
    "embedded-hal",
    "embedded-hal-nb",
    "nb",
    // crackbot-link: HMAC-SHA256 (RustCrypto), postcard and serde, all with default features off.
    "crackbot-link",
    "hmac",
    "sha2",
    "digest",
    "block-buffer",
    "crypto-common",
    "hybrid-array",
    "typenum",
    "ctutils",
    "cmov",
    "cpufeatures",
    "cfg-if",
    "postcard",
    "serde",
    "serde_core",
];

/// The robot path: the headless binary and the libraries it runs, with default features.
const ROBOT_PATH: &[&str] = &[
    "crackbot-cli",
    "crackbot-mission",
    "crackbot-acquisition",
    "crackbot-emulator",
    "crackbot-dsp",
    "crackbot-forest",
    "crackbot-tactile",
    "crackbot-vision",
    "crackbot-sim",
    "crackbot-planner",
    "crackbot-link",
    "crackbot-controller",
];

/// Crates the robot path must not compile by default.
const HEAVY: &[&str] = &[
    "plotters",
    "statrs",
    "egui",
    "eframe",
    "egui_plot",
    "winit",
    "wgpu",
    "glow",
    "zenoh",
    // The Foxglove live view's WebSocket server (feature `foxglove`).
    "tokio-tungstenite",
    // The ROS 2 arm's DDS (the controller's feature `ros2`).
    "ros2-client",
    "rustdds",
];

/// Direct dependencies allowed in a few crates only: (dependency, a crate that may have it).
const ONLY_IN: &[(&str, &str)] = &[
    ("plotters", "crackbot-plots"),
    ("egui", "crackbot-operator"),
    ("eframe", "crackbot-operator"),
    ("egui_plot", "crackbot-operator"),
    ("winit", "crackbot-operator"),
    ("statrs", "crackbot-tactile"),
    ("zenoh", "crackbot-telemetry"),
    ("foxglove", "crackbot-mcap"),
    ("ros2-client", "crackbot-controller"),
    // The mission's live ROS 2 topics (crackbot-rosbag's feature `live`).
    ("ros2-client", "crackbot-rosbag"),
];

/// Dependencies of binaries, not of library-only crates.
const BINARY_ONLY_DEPS: &[&str] = &["anyhow", "clap", "indicatif", "tracing-subscriber"];

fn cargo() -> Command {
    let mut cmd = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    cmd.current_dir(env!("CARGO_MANIFEST_DIR"));
    cmd
}

fn run(cmd: &mut Command) -> String {
    let out = cmd.output().expect("running cargo");
    assert!(
        out.status.success(),
        "{cmd:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("cargo prints UTF-8")
}

/// A workspace member as `cargo metadata --no-deps` describes it.
struct Package {
    manifest: String,
    has_lib: bool,
    has_bin: bool,
    /// (name, kind: "normal" | "build" | "dev", optional)
    deps: Vec<(String, String, bool)>,
}

fn workspace() -> BTreeMap<String, Package> {
    let text = run(cargo().args(["metadata", "--format-version", "1", "--no-deps", "--locked"]));
    let meta: Value = serde_json::from_str(&text).expect("cargo metadata JSON");
    let mut out = BTreeMap::new();
    for p in meta["packages"].as_array().expect("packages") {
        let kinds: Vec<&str> = p["targets"]
            .as_array()
            .expect("targets")
            .iter()
            .flat_map(|t| t["kind"].as_array().expect("kind").iter())
            .filter_map(Value::as_str)
            .collect();
        let deps = p["dependencies"]
            .as_array()
            .expect("dependencies")
            .iter()
            .map(|d| {
                (
                    d["name"].as_str().expect("name").to_string(),
                    d["kind"].as_str().unwrap_or("normal").to_string(),
                    d["optional"].as_bool().unwrap_or(false),
                )
            })
            .collect();
        out.insert(
            p["name"].as_str().expect("name").to_string(),
            Package {
                manifest: p["manifest_path"].as_str().expect("manifest").to_string(),
                has_lib: kinds.iter().any(|k| k.contains("lib")),
                has_bin: kinds.contains(&"bin"),
                deps,
            },
        );
    }
    out
}

fn layer_of(name: &str) -> Option<usize> {
    LAYERS.iter().position(|(_, crates)| crates.contains(&name))
}

/// The lines of `cargo tree -p package -e edges` (no prefix), for its default features.
fn tree_lines(package: &str, edges: &str) -> Vec<String> {
    let text = run(cargo().args([
        "tree", "--locked", "-p", package, "-e", edges, "--prefix", "none",
    ]));
    text.lines().map(str::to_string).collect()
}

/// The crate names of `cargo tree -p package -e edges`.
fn tree_names(package: &str, edges: &str) -> BTreeSet<String> {
    tree_lines(package, edges)
        .iter()
        .filter_map(|l| l.split_whitespace().next())
        .map(str::to_string)
        .collect()
}

/// The crates `package` compiles for its normal build with default features.
fn normal_tree(package: &str) -> BTreeSet<String> {
    tree_names(package, "normal")
}

/// The crates linked into `package`'s normal build (what its proc macros use to run at compile
/// time left out: `prost-derive` runs on `anyhow`, and nothing of it is in the library).
fn linked_tree(package: &str) -> BTreeSet<String> {
    tree_names(package, "normal,no-proc-macro")
}

#[test]
fn every_crate_depends_only_on_lower_layers() {
    let ws = workspace();
    let mut problems = Vec::new();
    for (name, p) in &ws {
        let Some(layer) = layer_of(name) else {
            problems.push(format!(
                "{name} is in no layer: place it in LAYERS of tests/layering.rs"
            ));
            continue;
        };
        for (dep, kind, _) in &p.deps {
            if kind == "dev" || !ws.contains_key(dep) {
                continue;
            }
            match layer_of(dep) {
                Some(l) if l < layer => {}
                Some(l) => problems.push(format!(
                    "{name} (layer {layer}: {}) depends on {dep} (layer {l}: {}), which is not below it",
                    LAYERS[layer].0, LAYERS[l].0
                )),
                None => {} // reported as a crate without a layer
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn no_crate_depends_on_a_binary_crate() {
    let ws = workspace();
    let binaries: BTreeSet<&String> = ws
        .iter()
        .filter(|(_, p)| p.has_bin && !p.has_lib)
        .map(|(n, _)| n)
        .collect();
    assert!(binaries.iter().any(|n| n.as_str() == "crackbot-cli"));
    let mut problems = Vec::new();
    for (name, p) in &ws {
        for (dep, kind, _) in &p.deps {
            if binaries.contains(dep) {
                problems.push(format!("{name} depends ({kind}) on the binary crate {dep}"));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn no_std_crates_stay_no_std() {
    let ws = workspace();
    for name in NO_STD {
        let p = ws.get(*name).unwrap_or_else(|| panic!("{name} is missing"));
        let lib = Path::new(&p.manifest)
            .parent()
            .expect("crate folder")
            .join("src/lib.rs");
        let source = std::fs::read_to_string(&lib).expect("reading lib.rs");
        assert!(
            source.lines().any(|l| l.trim() == "#![no_std]"),
            "{} lost its #![no_std]",
            lib.display()
        );
        // Proc-macros run on the build host; what is compiled for the target must be no_std.
        let lines = tree_lines(name, "normal,no-proc-macro,features");
        let foreign: BTreeSet<&str> = lines
            .iter()
            .filter_map(|l| l.split_whitespace().next())
            .filter(|c| !NO_STD_ALLOWED.contains(c))
            .collect();
        assert!(
            foreign.is_empty(),
            "{name} pulls in {foreign:?}, not on the no_std allow-list of tests/layering.rs"
        );
        let with_std: Vec<&String> = lines
            .iter()
            .filter(|l| l.contains("feature \"std\""))
            .collect();
        assert!(
            with_std.is_empty(),
            "{name} turns on the std feature of a dependency: {with_std:?}"
        );
    }
}

#[test]
fn the_robot_path_builds_without_research_gui_or_fleet_crates() {
    let mut problems = Vec::new();
    for name in ROBOT_PATH {
        let tree = normal_tree(name);
        assert!(tree.contains(*name), "cargo tree of {name} lists {tree:?}");
        for heavy in HEAVY {
            if tree.contains(*heavy) {
                problems.push(format!(
                    "{name} compiles {heavy} in its default build (put it behind a feature)"
                ));
            }
        }
        // Trial scoring, scene geometry and the experiment tables are the research crate's.
        if tree.contains("crackbot-research") {
            problems.push(format!("{name} compiles crackbot-research"));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The crates whose evaluation (scoring, metrics, benchmarks, the paper's protocols) sits
/// behind their cargo feature `research`, and that feature.
const EVALUATED: &[(&str, &str)] = &[
    ("crackbot-tactile", "research"),
    ("crackbot-vision", "research"),
];

#[test]
fn the_robots_default_build_compiles_no_evaluation_module() {
    let features = tree_lines("crackbot-cli", "features");
    for (krate, feature) in EVALUATED {
        let on = format!("{krate} feature \"{feature}\"");
        assert!(
            !features.iter().any(|l| l.starts_with(&on)),
            "the robot's build turns on {krate}'s evaluation (feature `{feature}`):\n{}",
            features.join("\n")
        );
    }
    // The evaluation modules are behind the feature: a crate that turns it on would compile
    // them, and they are declared only under it. The tactile models' own evaluation (`eval`,
    // `evaluation`, `metrics`: held-out accuracy and width error, no statistics crate) is the
    // robot's since a finger's commissioning judges its models (`crackbot commission`); the
    // paper's grid, its statistics and the run-time sweep stay research.
    let sources = [
        (
            "crates/tactile/src/lib.rs",
            &["paper", "stats", "tradeoff"][..],
        ),
        (
            "crates/vision/src/lib.rs",
            &[
                "benchmark",
                "coco",
                "pieces",
                "pixel",
                "scene_recall",
                "tradeoff",
            ][..],
        ),
    ];
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    for (file, modules) in sources {
        let text = std::fs::read_to_string(root.join(file)).expect("a crate root");
        for m in modules {
            let gated = format!("#[cfg(feature = \"research\")]\npub mod {m};");
            assert!(
                text.contains(&gated),
                "{file}: `{m}` is not behind the feature `research`"
            );
        }
    }
}

/// The simulated rig's crates: the robot's default build has them for its built-in scene; the
/// robot built for hardware only must not compile them.
const SIMULATED_RIG: &[&str] = &["crackbot-sim", "crackbot-controller", "crackbot-emulator"];

#[test]
fn the_robot_without_the_simulator_feature_compiles_no_simulated_rig() {
    let tree = |args: &[&str]| -> BTreeSet<String> {
        let mut cmd = cargo();
        cmd.args([
            "tree",
            "--locked",
            "-p",
            "crackbot-cli",
            "-e",
            "normal",
            "--prefix",
            "none",
        ]);
        run(cmd.args(args))
            .lines()
            .filter_map(|l| l.split_whitespace().next())
            .map(str::to_string)
            .collect()
    };
    let hardware_only = tree(&["--no-default-features"]);
    for needed in [
        "crackbot-mission",
        "crackbot-link",
        "crackbot-acquisition",
        "crackbot-vision",
    ] {
        assert!(
            hardware_only.contains(needed),
            "the hardware-only robot lacks {needed}"
        );
    }
    let found: Vec<_> = SIMULATED_RIG
        .iter()
        .filter(|c| hardware_only.contains(**c))
        .collect();
    assert!(
        found.is_empty(),
        "crackbot-cli --no-default-features compiles {found:?}: keep them behind the `sim` feature"
    );
    // And the default build has them: the robot's built-in scene is the simulator's.
    let default = tree(&[]);
    assert!(
        SIMULATED_RIG.iter().all(|c| default.contains(*c)),
        "{default:?}"
    );
}

#[test]
fn the_research_cli_builds_without_gui_or_fleet_crates() {
    let tree = normal_tree("crackbot-lab");
    assert!(tree.contains("crackbot-lab"), "cargo tree lists {tree:?}");
    let found: Vec<_> = HEAVY
        .iter()
        .filter(|h| !matches!(**h, "plotters" | "statrs") && tree.contains(**h))
        .collect();
    assert!(found.is_empty(), "crackbot-lab compiles {found:?}");
}

/// The crates that depend directly on `dep` in `crackbot-cli` built with `features`.
fn dependants_in_the_robot(features: &str, dep: &str) -> BTreeSet<String> {
    let with = run(cargo().args([
        "tree",
        "-p",
        "crackbot-cli",
        "--features",
        features,
        "-e",
        "normal",
        "--prefix",
        "none",
        "-i",
        dep,
        "--depth",
        "1",
    ]));
    with.lines()
        .skip(1)
        .filter_map(|l| l.split_whitespace().next())
        .map(str::to_string)
        .collect()
}

#[test]
fn the_robots_telemetry_feature_brings_zenoh_and_only_through_the_telemetry_crate() {
    assert_eq!(
        dependants_in_the_robot("telemetry", "zenoh"),
        BTreeSet::from(["crackbot-telemetry".to_string()]),
        "zenoh's dependants in crackbot-cli --features telemetry"
    );
}

#[test]
fn the_robots_foxglove_feature_brings_the_websocket_server_only_through_the_log_crate() {
    assert_eq!(
        dependants_in_the_robot("foxglove", "tokio-tungstenite"),
        BTreeSet::from(["foxglove".to_string()]),
        "tokio-tungstenite's dependants in crackbot-cli --features foxglove"
    );
    assert_eq!(
        dependants_in_the_robot("foxglove", "foxglove"),
        BTreeSet::from(["crackbot-mcap".to_string()]),
        "the Foxglove SDK's dependants in crackbot-cli --features foxglove"
    );
}

#[test]
fn heavy_dependencies_live_in_their_own_crate() {
    let ws = workspace();
    let mut problems = Vec::new();
    for (name, p) in &ws {
        for (dep, kind, _) in &p.deps {
            if kind == "dev" {
                continue;
            }
            let owners: Vec<&str> = ONLY_IN
                .iter()
                .filter(|(d, _)| d == dep)
                .map(|(_, o)| *o)
                .collect();
            if !owners.is_empty() && !owners.contains(&name.as_str()) {
                problems.push(format!(
                    "{name} depends on {dep}; only {} may",
                    owners.join(", ")
                ));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn libraries_leave_errors_text_and_progress_bars_to_binaries() {
    let ws = workspace();
    let mut problems = Vec::new();
    for (name, p) in &ws {
        if !p.has_lib || name == "crackbot-tests" {
            continue;
        }
        // A crate with a library and a binary keeps its binary's dependencies optional, behind
        // a feature the binary requires, so that users of the library do not compile them.
        for (dep, kind, optional) in &p.deps {
            if kind != "dev" && !optional && BINARY_ONLY_DEPS.contains(&dep.as_str()) {
                problems.push(format!(
                    "the library {name} depends on {dep}: errors as thiserror enums, progress \
                     through callbacks, argument parsing in binaries (a binary of the same \
                     crate takes it through an optional feature)"
                ));
            }
        }
    }
    for name in ROBOT_PATH {
        let p = &ws[*name];
        if p.has_bin {
            continue;
        }
        for dep in linked_tree(name) {
            if BINARY_ONLY_DEPS.contains(&dep.as_str()) {
                problems.push(format!(
                    "the library {name} compiles {dep} by default (through a dependency's \
                     binary features?)"
                ));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
