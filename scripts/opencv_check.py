#!/usr/bin/env python3
"""OpenCV's calibration of the views crackbot-calib was given, as JSON on standard output.

    opencv_check.py calibrate VIEWS.json WIDTH HEIGHT
    opencv_check.py images FOLDER TARGET.toml

`images`: OpenCV's own end to end: its ArUco detector (dictionary DICT_APRILTAG_36h11, sub-pixel
corner refinement) finds the tags in every .png of FOLDER (sorted), their corners are matched to
the target's by id (TARGET.toml: crates/calib-target/docs/target.md), and the camera is calibrated
as below. Pixels in OpenCV's convention (a pixel's centre is integer; crackbot's cx = OpenCV's
+ 0.5). Adds "tags": the tags found per image.

VIEWS.json: a list of views, each {"target": [[x_mm, y_mm], ...], "image": [[u, v], ...]}
(crackbot_calib::View). OpenCV fits the same model: fx, fy, cx, cy (no skew) and k1, k2, p1, p2
with k3 fixed at 0 (crackbot's default), from its own initial guess. Output:
{"fx", "fy", "cx", "cy", "dist": [k1, k2, p1, p2, k3], "rms_px", "rvecs", "tvecs"}.
"""
import json
import sys

import cv2
import numpy as np


def fit(views, size):
    """cv2.calibrateCamera on crackbot_calib::View-like dicts: the fit as a dict."""
    objects = [
        np.array([[x, y, 0.0] for x, y in v["target"]], dtype=np.float32) for v in views
    ]
    images = [np.array(v["image"], dtype=np.float32) for v in views]
    rms, k, dist, rvecs, tvecs = cv2.calibrateCamera(
        objects, images, size, None, None, flags=cv2.CALIB_FIX_K3
    )
    dist = dist.ravel().tolist()
    return {
        "fx": k[0, 0],
        "fy": k[1, 1],
        "cx": k[0, 2],
        "cy": k[1, 2],
        "dist": (dist + [0.0] * 5)[:5],
        "rms_px": rms,
        "rvecs": [r.ravel().tolist() for r in rvecs],
        "tvecs": [t.ravel().tolist() for t in tvecs],
    }


def calibrate(path, width, height):
    print(json.dumps(fit(json.load(open(path)), (width, height))))


def target_corners(spec, tag_id):
    """The black square's corners of tag `tag_id` in the target's frame (mm, y up the sheet),
    in the order OpenCV's ArUco returns them for its APRILTAG_36h11 dictionary: bottom-right,
    bottom-left, top-left, top-right as printed (its canonical tag is the library's turned 180°;
    found on the printed target: crackbot calibrate target --px-per-mm 4)."""
    k = tag_id - spec["first_id"]
    if not 0 <= k < spec["cols"] * spec["rows"]:
        return None
    pitch = spec["tag_mm"] + spec["gap_mm"]
    x0, y0, s = (k % spec["cols"]) * pitch, (k // spec["cols"]) * pitch, spec["tag_mm"]
    return [[x0 + s, y0], [x0, y0], [x0, y0 + s], [x0 + s, y0 + s]]


def images(folder, target):
    import pathlib
    import tomllib

    spec = tomllib.loads(pathlib.Path(target).read_text())
    detector = cv2.aruco.ArucoDetector(
        cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11),
        cv2.aruco.DetectorParameters(),
    )
    params = detector.getDetectorParameters()
    params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    detector.setDetectorParameters(params)
    views, tags, size = [], [], None
    for path in sorted(pathlib.Path(folder).glob("*.png")):
        grey = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
        size = (grey.shape[1], grey.shape[0])
        corners, ids, _ = detector.detectMarkers(grey)
        view = {"target": [], "image": []}
        for c, i in zip(corners, [] if ids is None else ids.ravel()):
            mm = target_corners(spec, int(i))
            if mm is not None:
                view["target"] += mm
                view["image"] += c.reshape(4, 2).tolist()
        tags.append(len(view["target"]) // 4)
        if len(view["target"]) >= 16:
            views.append(view)
    result = fit(views, size)
    result["tags"] = tags
    print(json.dumps(result))


def main():
    if len(sys.argv) == 5 and sys.argv[1] == "calibrate":
        calibrate(sys.argv[2], int(sys.argv[3]), int(sys.argv[4]))
    elif len(sys.argv) == 4 and sys.argv[1] == "images":
        images(sys.argv[2], sys.argv[3])
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
