//! Eq. 1 on the real crack masks of `../shared/data/cracks` (crackforest and uav75, train and
//! val; quaywall has boxes only): every mask's crack pixels are the COCO file's `crack_pixels`,
//! `w̄` measured two independent ways agrees, `L̄` is the centre-line length eq. 1 approximates,
//! and the figures stay where they were measured (printed with `--nocapture`, next to the
//! paper's).

#[path = "support/masks.rs"]
mod masks;

use crackbot_planner::{mean_crack_length, scan_rows_count, CrackLengthEstimate, PAPER_EQ1};

fn estimate(ds: &'static str, splits: &[&'static str]) -> CrackLengthEstimate {
    let cracks = crackbot_datasets::require(crackbot_datasets::CRACKS);
    let all: Vec<masks::RealMask> = splits
        .iter()
        .flat_map(|s| masks::read_masks(&cracks, ds, s))
        .collect();
    for m in &all {
        assert_eq!(
            m.mask.crack_pixels(),
            m.recorded_crack_pixels,
            "{}/{} ({}): crack pixels differ from the COCO file",
            m.dataset,
            m.file,
            m.split
        );
    }
    mean_crack_length(all.into_iter().map(|m| m.mask)).expect("eq. 1")
}

#[test]
fn eq1_on_the_real_masks() {
    println!("| data | N_c | image px | Ā px | w̄ px (A/S) | w̄ px (distance) | L̄ px | mean S px | L̄ / H | L̄ mm (h = 100) | N_s γ=.25/.5/.75 |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    let row = |name: &str, e: &CrackLengthEstimate| {
        let l_mm = e.mean_length_mm(100.0);
        let ns: Vec<String> = [0.25, 0.5, 0.75]
            .iter()
            .map(|g| scan_rows_count(100.0, *g, l_mm).unwrap().to_string())
            .collect();
        println!(
            "| {name} | {} | {:.0} | {:.1} | {:.2} | {:.2} | {:.1} | {:.1} | {:.3} | {:.1} | {} |",
            e.n_c,
            e.mean_image_px,
            e.mean_area_px,
            e.mean_width_px,
            e.mean_distance_width_px,
            e.mean_length_px,
            e.mean_skeleton_length_px,
            e.mean_length_fraction_of_height,
            l_mm,
            ns.join("/")
        );
    };
    let p = PAPER_EQ1;
    let paper_frac = p.mean_length_px / p.image_side_px;
    println!(
        "| paper (Özgenel 227², by hand) | {} | {:.0} | {:.0} | {:.0} | | {:.2} | | {:.3} (÷227) / {:.3} (÷480) | {:.1} / {:.2} | 7/4/3 (÷227), 13/7/5 (÷480) |",
        p.n_c, p.image_px, p.mean_area_px, p.mean_width_px, p.mean_length_px, paper_frac,
        p.mean_length_px / p.camera_height_px, paper_frac * 100.0, p.mean_length_px / p.camera_height_px * 100.0
    );
    let mut by_dataset = Vec::new();
    for ds in masks::DATASETS {
        for split in masks::SPLITS {
            row(&format!("{ds} {split}"), &estimate(ds, &[split]));
        }
        let e = estimate(ds, &masks::SPLITS);
        row(&format!("{ds} train+val"), &e);
        by_dataset.push((ds, e));
    }
    for (ds, e) in &by_dataset {
        assert_eq!(e.n_c, e.masks, "{ds}: every image holds a crack");
        // The two width measures agree to within a pixel (different definitions: area over
        // length counts a diagonal 1-px line as 0.7 px wide, the distance transform as 1).
        assert!(
            (e.mean_width_px - e.mean_distance_width_px).abs() < 1.0,
            "{ds}: {e:?}"
        );
        // Eq. 1 with the mean width comes back to the centre line's length (the paper's
        // assumption: a crack is lines of one width).
        assert!(
            (e.mean_length_px / e.mean_skeleton_length_px - 1.0).abs() < 0.05,
            "{ds}: {e:?}"
        );
    }
    // Where the figures were measured (guards the thinning, the length and the reading).
    let (cf, uav) = (&by_dataset[0].1, &by_dataset[1].1);
    assert_eq!((cf.n_c, uav.n_c), (88, 57));
    assert!((3.0..3.2).contains(&cf.mean_width_px), "{cf:?}");
    assert!((1.1..1.2).contains(&uav.mean_width_px), "{uav:?}");
    assert!((820.0..880.0).contains(&cf.mean_length_px), "{cf:?}");
    assert!((740.0..780.0).contains(&uav.mean_length_px), "{uav:?}");
    // Both datasets' cracks are several times longer than the paper's, relative to their
    // images: crack networks and road-long cracks, not close-up crops.
    assert!(cf.mean_length_fraction_of_height > 2.0 && uav.mean_length_fraction_of_height > 1.0);
}
