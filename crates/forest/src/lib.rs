//! Tactile surface classifiers for crackbot.
//!
//! The robot classifies surfaces (flat / crack / bump / wavy, or the crack width in mm) from windowed MAV
//! features of the fibre-optic finger (D1, D2, P in ADC counts), like the paper's random forest (100
//! trees), KNN (k = 5) and QDA. This crate holds:
//!
//! * [`Dataset`] / [`RegressionDataset`]: validated row-major `f32` features (finite, consistent lengths).
//! * [`RandomForest::fit`] / [`RandomForestRegressor::fit`]: a fast, deterministic, parallel random-forest
//!   trainer ([`ForestParams`]), written here because linfa's forest samples features once per tree, trains
//!   serially and takes seconds per fully grown tree.
//! * [`RandomForest`] / [`RandomForestRegressor`]: flat inference models, allocation-free per row, with a
//!   batch API, and a versioned, checksummed binary file format ([`mod@format`]).
//! * [`Knn`] and [`Qda`]: the paper's other two classifiers, behind the same [`Classifier`] trait.
//! * [`sklearn`]: import of a scikit-learn forest exported to JSON by `sklearn/export_forest.py`.
//! * [`synthetic`]: data generators for tests, examples and benchmarks.
//!
//! # Training design
//!
//! Each tree follows scikit-learn's `RandomForestClassifier` semantics: bootstrap of `n_rows` draws,
//! Gini (or MSE) criterion, `max_features` candidates drawn **per split** (constant features skipped and not
//! counted), thresholds at midpoints between consecutive distinct values, children with at least
//! `min_samples_leaf` distinct samples, leaves holding class probabilities (weighted class counts / total).
//! Speed comes from pre-sorting: every feature is argsorted once for the forest; each tree filters these
//! orders by its bootstrap counts (bootstrap duplicates become integer weights) and keeps one sorted list
//! per feature, partitioned stably down the tree, so a level costs O(n · n_features) and nothing is
//! re-sorted. The Gini scan keeps integer class counts and sums of squared counts, so it is exact.
//! Nodes are emitted in depth-first pre-order, which is the inference layout itself.
//!
//! Determinism: tree `i` draws from a ChaCha8 stream `(seed, i)`; trees are built independently in rayon
//! and collected in order, so a model depends on the data and the parameters only, not on the thread
//! count. Nothing is drawn: [`RandomForest::fit_with_progress`] reports each finished tree to a callback (a
//! binary draws the progress bar), unless [`ForestParams::quiet`] is set.
//!
//! # Inference design
//!
//! All nodes of all trees are one contiguous `Vec<Node>` of 12-byte nodes (`feature`, `f32` threshold,
//! right child; the left child is the next node), leaves index a probability table. The rule is
//! scikit-learn's `x[feature] <= threshold` → left (NaN goes right); the child is chosen with
//! `std::hint::select_unpredictable` (a conditional move: the comparison is a coin flip for the branch
//! predictor). A single row walks an 8-byte copy of the nodes (leaves step to themselves), sixteen trees
//! in lockstep to overlap their cache misses, summing their leaves in registers. The batch path of
//! models that do not fit that copy takes blocks of 8192 rows and, tree by tree, moves all rows of the
//! block down one level at a time, compacting the list of unfinished rows without branches: the tree
//! stays in L2 for the whole block and the independent iterations overlap their memory accesses. Soft voting sums leaf probabilities in `f32`
//! in tree order on both paths, so they agree bit for bit. Validation at load time (children strictly
//! after their parent and inside their tree, feature and leaf indices in range) guarantees that traversal
//! terminates and stays in bounds; no `unsafe` is used.
//!
//! # Performance (2-core shared VM, release; see `examples/`)
//!
//! * Training, 100 fully grown trees, 75k × 3 rows, 4 classes: 0.83–1.1 s on 2 threads, 1.9 s on 1
//!   (`cargo run -p crackbot-research --release --example train_timing`). On identical data scikit-learn
//!   1.9.1 took 5.35 s (`n_jobs=2`) and 11.45 s (`n_jobs=1`), with the same tree sizes (12.2k nodes).
//! * Prediction, same forest (7.2k nodes per tree, 8.7 MB of nodes): single row median ≈ 5–6 µs,
//!   `predict_batch` ≈ 0.18–0.27 M rows/s on one core (`--example predict_timing`); scikit-learn's
//!   `predict` (n_jobs=1) ran at ≈ 47k rows/s here. This VM is slow at memory: a dependent load costs
//!   3.5 ns in L1, 10 ns at 1 MB and 140–250 ns beyond 4 MB, so the forest does not fit in any fast
//!   cache and single-row latency is dominated by misses.
//!
//! # Example
//!
//! ```
//! use crackbot_forest::{synthetic, Classifier, ForestParams, RandomForest};
//!
//! let data = synthetic::blobs(2_000, 3, 4, 40.0, 1)?;
//! let (train, test) = data.split_at(1_500)?;
//! let params = ForestParams::classifier().n_trees(20).seed(7).quiet(true);
//! let forest = RandomForest::fit(&train, &params)?;
//! let class = forest.predict(test.row(0).unwrap_or(&[]));
//! assert!(class < 4);
//! let bytes = forest.to_bytes();
//! assert_eq!(RandomForest::from_bytes(&bytes)?, forest);
//! # Ok::<(), crackbot_forest::ForestError>(())
//! ```

mod classifier;
mod data;
mod error;
pub mod flat;
mod forest;
pub mod format;
mod knn;
mod params;
mod qda;
mod regressor;
pub mod sklearn;
pub mod synthetic;
mod train;

pub use classifier::{accuracy, argmax, Classifier};
pub use data::{Dataset, RegressionDataset};
pub use error::{ForestError, FormatError, Result};
pub use flat::{Node, LEAF};
pub use forest::RandomForest;
pub use knn::{Knn, KnnParams};
pub use params::{ForestParams, MaxFeatures};
pub use qda::{Qda, QdaParams};
pub use regressor::RandomForestRegressor;
pub use train::TrainProgress;
