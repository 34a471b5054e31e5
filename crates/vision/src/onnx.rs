//! The crack detector trained in `models/detector/`, run through ONNX Runtime.
//!
//! `ort` is built with `load-dynamic`: the binary does not link ONNX Runtime; the shared library
//! `libonnxruntime.so.1.31.1` (from the `onnxruntime==1.31.1` wheel on PyPI) is loaded on first use
//! from, in order:
//! 1. `ORT_DYLIB_PATH` (the library file itself);
//! 2. the project's own install, which `scripts/setup.sh` makes on first use:
//!    `$CRACKBOT_CACHE_DIR` (default `~/.cache/crackbot`)`/ort-venv/lib/python3*/site-packages/
//!    onnxruntime/capi/libonnxruntime.so.*`.
//!
//! Missing or mismatched runtimes give a [`VisionError::Runtime`] that names the version expected
//! and how to get it, never a panic.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use ort::session::Session;
use ort::value::TensorRef;

use crate::box_head::{with_head_boxes, BoxHeadMaps, HEAD_STRIDE, REG_CHANNELS};
use crate::crack_map::{map_detections, CrackMap, MAP_STRIDE};
use crate::preprocess::{letterbox, postprocess, Letterbox, PostprocessParams};
use crate::{Detection, Detector, VisionError};

/// What a model returns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModelOutput {
    /// `detections` `[1, N, 5]`: boxes and scores (the box detector).
    Boxes,
    /// `crack_map` `[1, 1, S/2, S/2]`: crack probabilities (the segmentation detector; see
    /// [`crate::crack_map`]).
    CrackMap,
}

impl ModelOutput {
    /// The output tensor's name.
    pub fn tensor_name(self) -> &'static str {
        match self {
            ModelOutput::Boxes => "detections",
            ModelOutput::CrackMap => "crack_map",
        }
    }
}

/// The ONNX Runtime version this build expects (the `api-31` feature of `ort` refuses older ones).
pub const ORT_VERSION: &str = "1.31.1";

/// How to get the runtime, appended to every "runtime not found" error.
const HOW_TO_FIX: &str =
    "run `bash scripts/setup.sh` (installs the onnxruntime==1.31.1 wheel into \
~/.cache/crackbot/ort-venv), or `pip install onnxruntime==1.31.1` and set ORT_DYLIB_PATH to its \
onnxruntime/capi/libonnxruntime.so.1.31.1";

/// The ONNX Runtime library to load: `ORT_DYLIB_PATH`, else the project's own install.
pub fn runtime_library() -> Result<PathBuf, VisionError> {
    if let Some(p) = std::env::var_os("ORT_DYLIB_PATH") {
        let p = PathBuf::from(p);
        if p.is_file() {
            return Ok(p);
        }
        return Err(VisionError::Runtime(format!(
            "ORT_DYLIB_PATH={} is not a file (it must name libonnxruntime.so.{ORT_VERSION} itself); {HOW_TO_FIX}",
            p.display()
        )));
    }
    let cache = std::env::var_os("CRACKBOT_CACHE_DIR")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache/crackbot")));
    let searched = cache
        .as_ref()
        .map(|c| c.join("ort-venv/lib/python3*/site-packages/onnxruntime/capi"));
    if let Some(found) = cache.as_deref().and_then(find_in_venv) {
        return Ok(found);
    }
    Err(VisionError::Runtime(format!(
        "ONNX Runtime {ORT_VERSION} not found (ORT_DYLIB_PATH is unset; looked in {}); {HOW_TO_FIX}",
        searched.map_or_else(|| "no cache folder: HOME unset".into(), |s| s.display().to_string())
    )))
}

/// `libonnxruntime.so.*` of the wheel in `<cache>/ort-venv`.
fn find_in_venv(cache: &Path) -> Option<PathBuf> {
    let lib = cache.join("ort-venv/lib");
    for py in std::fs::read_dir(&lib).ok()?.flatten() {
        let capi = py.path().join("site-packages/onnxruntime/capi");
        let Ok(entries) = std::fs::read_dir(&capi) else {
            continue;
        };
        let mut libs: Vec<PathBuf> = entries
            .flatten()
            .map(|e| e.path())
            .filter(|p| {
                p.file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(|n| n.starts_with("libonnxruntime.so."))
            })
            .collect();
        libs.sort();
        if let Some(l) = libs.pop() {
            return Some(l);
        }
    }
    None
}

/// The process-wide ONNX Runtime environment. A library that is not found is looked for again on
/// the next call; once one has been loaded (or failed to load), that outcome is kept: a process
/// can load ONNX Runtime only once.
fn environment() -> Result<&'static ort::environment::Environment, VisionError> {
    static ENV: OnceLock<Result<ort::environment::Environment, String>> = OnceLock::new();
    if ENV.get().is_none() {
        runtime_library()?;
    }
    ENV.get_or_init(|| {
        let path = runtime_library().map_err(|e| e.to_string())?;
        let builder = ort::init_from(&path).map_err(|e| {
            format!(
                "loading ONNX Runtime from {}: {e}; this build needs {ORT_VERSION}: {HOW_TO_FIX}",
                path.display()
            )
        })?;
        builder
            .with_name("crackbot")
            .build()
            .map_err(|e| format!("starting ONNX Runtime from {}: {e}", path.display()))
    })
    .as_ref()
    .map_err(|e| VisionError::Runtime(e.clone()))
}

/// The trained detector (`models/detector/crack-detector-*.onnx`) behind [`Detector`].
pub struct OnnxDetector {
    session: Session,
    size: usize,
    output: ModelOutput,
    box_head: bool,
    params: PostprocessParams,
    name: String,
}

impl std::fmt::Debug for OnnxDetector {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OnnxDetector")
            .field("name", &self.name)
            .field("size", &self.size)
            .field("output", &self.output)
            .field("box_head", &self.box_head)
            .field("params", &self.params)
            .finish()
    }
}

impl OnnxDetector {
    /// Loads `model` (one input `images` `[1, 3, S, S]` f32; a first output `detections`
    /// `[1, N, 5]` or `crack_map` `[1, 1, S/2, S/2]` f32, and for a crack-map model with a box
    /// head also `box_heat` and `box_reg`, [`crate::box_head`]), running it on `threads` intra-op
    /// threads.
    pub fn load(
        model: &Path,
        params: PostprocessParams,
        threads: usize,
    ) -> Result<Self, VisionError> {
        let env = environment()?;
        let bytes = std::fs::read(model).map_err(VisionError::io(model))?;
        let fail = |e: &dyn std::fmt::Display| {
            VisionError::Runtime(format!("model {}: {e}", model.display()))
        };
        let mut builder = Session::builder(env).map_err(|e| fail(&e))?;
        builder = builder
            .with_intra_threads(threads.max(1))
            .map_err(|e| fail(&e))?;
        let session = builder.commit_from_memory(&bytes).map_err(|e| fail(&e))?;
        let inputs = session.inputs();
        let outputs = session.outputs();
        if inputs.len() != 1 || inputs[0].name() != "images" {
            return Err(fail(&format!(
                "expected one input named `images`, found {:?}",
                inputs
                    .iter()
                    .map(ort::value::Outlet::name)
                    .collect::<Vec<_>>()
            )));
        }
        let output = match outputs.first().map(ort::value::Outlet::name) {
            Some("detections") => ModelOutput::Boxes,
            Some("crack_map") => ModelOutput::CrackMap,
            _ => {
                return Err(fail(&format!(
                    "expected an output named `detections` (boxes) or `crack_map` (a crack map), found {:?}",
                    outputs.iter().map(ort::value::Outlet::name).collect::<Vec<_>>()
                )))
            }
        };
        let names: Vec<&str> = outputs.iter().map(ort::value::Outlet::name).collect();
        let box_head = match (names.contains(&"box_heat"), names.contains(&"box_reg")) {
            (false, false) => false,
            (true, true) if output == ModelOutput::CrackMap => true,
            _ => {
                return Err(fail(&format!(
                    "a box head needs both outputs `box_heat` and `box_reg` beside `crack_map`, found {names:?}"
                )))
            }
        };
        let shape: Vec<i64> = inputs[0]
            .dtype()
            .tensor_shape()
            .map(|s| s.iter().copied().collect())
            .unwrap_or_default();
        let size = match shape.as_slice() {
            [1, 3, h, w]
                if h == w
                    && *h > 0
                    && (*h as usize).is_multiple_of(if box_head {
                        HEAD_STRIDE
                    } else {
                        MAP_STRIDE
                    }) =>
            {
                *h as usize
            }
            _ => {
                return Err(fail(&format!(
                    "input `images` has shape {shape:?}, expected [1, 3, S, S] with a fixed S"
                )))
            }
        };
        let stem = model
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("model");
        Ok(Self {
            session,
            size,
            output,
            box_head,
            params,
            name: format!("onnx:{stem}"),
        })
    }

    /// What the model returns.
    pub fn output(&self) -> ModelOutput {
        self.output
    }

    /// Whether the model has a box head (outputs `box_heat` and `box_reg`, [`crate::box_head`]).
    pub fn has_box_head(&self) -> bool {
        self.box_head
    }

    /// The model's input side `S` in pixels.
    pub fn input_size(&self) -> usize {
        self.size
    }

    /// Post-processing in use.
    pub fn params(&self) -> &PostprocessParams {
        &self.params
    }

    /// Changes the post-processing (e.g. a lower threshold for mAP evaluation).
    pub fn set_params(&mut self, params: PostprocessParams) {
        self.params = params;
    }

    /// Runs the model on an input tensor (`3·S·S` values, NCHW) and returns its output: the raw
    /// `detections` rows (`N × 5`) of a box model, or the `(S/2)²` cells of a crack map.
    pub fn run_tensor(&mut self, tensor: &[f32]) -> Result<Vec<f32>, VisionError> {
        let name = self.output.tensor_name();
        Ok(self.run(tensor, &[name])?.remove(0))
    }

    /// Runs the model on an input tensor and returns the outputs `names`, in that order, each
    /// checked against its expected shape.
    fn run(&mut self, tensor: &[f32], names: &[&str]) -> Result<Vec<Vec<f32>>, VisionError> {
        let s = self.size;
        if tensor.len() != 3 * s * s {
            return Err(VisionError::Shape {
                what: "the input tensor",
                got: tensor.len(),
                expected: 3 * s * s,
            });
        }
        let name = self.name.clone();
        let fail = |e: ort::Error| VisionError::Runtime(format!("{name}: {e}"));
        let input = TensorRef::from_array_view(([1usize, 3, s, s], tensor)).map_err(fail)?;
        let outputs = self
            .session
            .run(ort::inputs!["images" => input])
            .map_err(fail)?;
        let mut values = Vec::with_capacity(names.len());
        for &tensor_name in names {
            let out = outputs.get(tensor_name).ok_or_else(|| {
                VisionError::Runtime(format!("{name}: no `{tensor_name}` output"))
            })?;
            let (shape, data) = out.try_extract_tensor::<f32>().map_err(fail)?;
            let shape: Vec<i64> = shape.iter().copied().collect();
            check_shape(&name, tensor_name, &shape, s)?;
            values.push(data.to_vec());
        }
        Ok(values)
    }

    /// The crack map of `image` and, for a model with a box head, the head's outputs.
    fn crack_map_and_head(
        &mut self,
        image: &image::RgbImage,
    ) -> Result<(CrackMap, Option<BoxHeadMaps>), VisionError> {
        let (tensor, lb) = self.preprocess(image)?;
        if !(self.box_head && self.params.box_head) {
            return Ok((CrackMap::new(self.run_tensor(&tensor)?, lb)?, None));
        }
        let mut out = self.run(&tensor, &["crack_map", "box_heat", "box_reg"])?;
        let (reg, heat, map) = (out.remove(2), out.remove(1), out.remove(0));
        Ok((
            CrackMap::new(map, lb)?,
            Some(BoxHeadMaps::new(heat, reg, lb)?),
        ))
    }

    /// The crack map of `image` (crack-map models only).
    pub fn crack_map(&mut self, image: &image::RgbImage) -> Result<CrackMap, VisionError> {
        if self.output != ModelOutput::CrackMap {
            return Err(VisionError::WrongOutput {
                model: self.name.clone(),
                has: "boxes",
                wanted: "a crack map",
            });
        }
        let (tensor, lb) = self.preprocess(image)?;
        CrackMap::new(self.run_tensor(&tensor)?, lb)
    }

    /// The box head's outputs for `image` (models with a box head).
    pub fn box_head_maps(&mut self, image: &image::RgbImage) -> Result<BoxHeadMaps, VisionError> {
        if !self.box_head {
            return Err(VisionError::WrongOutput {
                model: self.name.clone(),
                has: "no box head",
                wanted: "box head outputs",
            });
        }
        let (tensor, lb) = self.preprocess(image)?;
        let mut out = self.run(&tensor, &["box_heat", "box_reg"])?;
        let (reg, heat) = (out.remove(1), out.remove(0));
        BoxHeadMaps::new(heat, reg, lb)
    }

    /// Letterboxes `image` for this model (see [`crate::preprocess`]).
    pub fn preprocess(
        &self,
        image: &image::RgbImage,
    ) -> Result<(Vec<f32>, Letterbox), VisionError> {
        letterbox(image, self.size)
    }
}

impl Detector for OnnxDetector {
    fn name(&self) -> String {
        self.name.clone()
    }

    fn detect(&mut self, image: &image::RgbImage) -> Result<Vec<Detection>, VisionError> {
        Ok(self.detect_with_map(image)?.0)
    }

    fn detect_with_map(
        &mut self,
        image: &image::RgbImage,
    ) -> Result<(Vec<Detection>, Option<CrackMap>), VisionError> {
        match self.output {
            ModelOutput::Boxes => {
                let (tensor, lb) = self.preprocess(image)?;
                let rows = self.run_tensor(&tensor)?;
                Ok((postprocess(&rows, &lb, &self.params)?, None))
            }
            ModelOutput::CrackMap => {
                let (map, head) = self.crack_map_and_head(image)?;
                let found = map_detections(&map, &self.params);
                let found = match head {
                    Some(head) if self.params.box_head => {
                        with_head_boxes(found, &head, &self.params)
                    }
                    _ => found,
                };
                Ok((found, Some(map)))
            }
        }
    }
}

/// Checks that output `tensor_name` of the model `model` at input side `s` has its contract's
/// shape: `detections` `[1, N, 5]`, `crack_map` `[1, 1, S/2, S/2]`, `box_heat` `[1, 1, S/8, S/8]`,
/// `box_reg` `[1, 4, S/8, S/8]`.
fn check_shape(model: &str, tensor_name: &str, shape: &[i64], s: usize) -> Result<(), VisionError> {
    let side = |stride: usize| (s / stride) as i64;
    let (ok, want) = match tensor_name {
        "detections" => (shape.len() == 3 && shape[2] == 5, "[1, N, 5]".to_string()),
        "crack_map" => {
            let c = side(MAP_STRIDE);
            (shape == [1, 1, c, c], format!("[1, 1, {c}, {c}]"))
        }
        "box_heat" | "box_reg" => {
            let c = side(HEAD_STRIDE);
            let k = if tensor_name == "box_heat" {
                1
            } else {
                REG_CHANNELS as i64
            };
            (shape == [1, k, c, c], format!("[1, {k}, {c}, {c}]"))
        }
        _ => (true, String::new()),
    };
    if ok {
        Ok(())
    } else {
        Err(VisionError::Runtime(format!(
            "{model}: `{tensor_name}` has shape {shape:?}, expected {want}"
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::check_shape;

    #[test]
    fn every_output_is_checked_against_its_contract_shape() {
        assert!(check_shape("m", "crack_map", &[1, 1, 160, 160], 320).is_ok());
        assert!(check_shape("m", "box_heat", &[1, 1, 40, 40], 320).is_ok());
        assert!(check_shape("m", "box_reg", &[1, 4, 40, 40], 320).is_ok());
        assert!(check_shape("m", "detections", &[1, 7, 5], 320).is_ok());
        for (name, shape) in [
            ("crack_map", vec![1, 1, 80, 80]),
            ("box_heat", vec![1, 1, 160, 160]),
            ("box_reg", vec![1, 2, 40, 40]),
            ("detections", vec![1, 7, 4]),
        ] {
            let err = check_shape("m", name, &shape, 320).unwrap_err().to_string();
            assert!(err.contains(name) && err.contains("expected"), "{err}");
        }
    }
}
