//! COCO detection files, the COCO detection metrics, and running a detector over a COCO dataset.
//!
//! * The file format (types, reading, validation, writing) is `crackbot_imaging::coco`,
//!   re-exported here: [`CocoDataset`], [`CocoImage`], [`CocoAnnotation`], [`CocoCategory`],
//!   [`CocoResult`], [`load_results`], [`parse_results`], [`save_results`].
//! * [`evaluate`]: the metrics, computed exactly as pycocotools' `COCOeval` (iouType `bbox`)
//!   does ([`CocoMetrics`]).
//! * [`detect_dataset`]: a [`Detector`](crate::Detector) over every image of a ground truth, as
//!   COCO results.

mod dataset;
mod eval;

pub use crackbot_imaging::coco::{
    load_results, parse_results, save_results, validate_results, CocoAnnotation, CocoCategory,
    CocoDataset, CocoImage, CocoResult,
};
pub use dataset::{coco_result, detect_dataset, detect_dataset_with_maps, Progress};
pub use eval::{evaluate, CocoMetrics};
