//! Reads the real crack masks of `../shared/data/cracks` (crackforest and uav75: the datasets
//! with masks) as [`BinaryMask`]s, with the `crack_pixels` their COCO files record.

use std::path::Path;

use crackbot_planner::BinaryMask;

/// One mask with where it came from.
pub struct RealMask {
    /// `crackforest` or `uav75`.
    pub dataset: &'static str,
    /// `train` or `val`.
    pub split: &'static str,
    /// The mask file, relative to the dataset.
    pub file: String,
    /// `crack_pixels` as the COCO file records it.
    pub recorded_crack_pixels: usize,
    /// The mask.
    pub mask: BinaryMask,
}

/// The datasets that have masks.
pub const DATASETS: [&str; 2] = ["crackforest", "uav75"];
/// Their splits here (the test split is held out and not in the folder).
pub const SPLITS: [&str; 2] = ["train", "val"];

/// Every mask of `dataset`'s `split`, in the COCO file's image order.
pub fn read_masks(cracks: &Path, dataset: &'static str, split: &'static str) -> Vec<RealMask> {
    let dir = cracks.join(dataset);
    let coco: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join(format!("{split}.json"))).expect("reading the COCO file"),
    )
    .expect("COCO JSON");
    coco["images"]
        .as_array()
        .expect("images")
        .iter()
        .map(|im| {
            let file = im["mask_file"].as_str().expect("mask_file").to_string();
            let img = image::open(dir.join(&file))
                .expect("decoding the mask")
                .to_luma8();
            let (w, h) = img.dimensions();
            assert_eq!(
                (u64::from(w), u64::from(h)),
                (
                    im["width"].as_u64().expect("width"),
                    im["height"].as_u64().expect("height")
                ),
                "{dataset}/{file}: size"
            );
            // 1-bit PNGs decode to 0 / 255; 1 (white) is crack.
            let pixels = img.pixels().map(|p| p.0[0] > 127).collect();
            RealMask {
                dataset,
                split,
                recorded_crack_pixels: im["crack_pixels"].as_u64().expect("crack_pixels") as usize,
                file,
                mask: BinaryMask::new(w as usize, h as usize, pixels).expect("mask"),
            }
        })
        .collect()
}
