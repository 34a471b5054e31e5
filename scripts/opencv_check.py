#!/usr/bin/env python3
"""OpenCV's calibration of the views crackbot-calib was given, as JSON on standard output.

    opencv_check.py calibrate VIEWS.json WIDTH HEIGHT

VIEWS.json: a list of views, each {"target": [[x_mm, y_mm], ...], "image": [[u, v], ...]}
(crackbot_calib::View). OpenCV fits the same model: fx, fy, cx, cy (no skew) and k1, k2, p1, p2
with k3 fixed at 0 (crackbot's default), from its own initial guess. Output:
{"fx", "fy", "cx", "cy", "dist": [k1, k2, p1, p2, k3], "rms_px", "rvecs", "tvecs"}.
"""
import json
import sys

import cv2
import numpy as np


def calibrate(path, width, height):
    views = json.load(open(path))
    objects = [
        np.array([[x, y, 0.0] for x, y in v["target"]], dtype=np.float32) for v in views
    ]
    images = [np.array(v["image"], dtype=np.float32) for v in views]
    rms, k, dist, rvecs, tvecs = cv2.calibrateCamera(
        objects, images, (width, height), None, None, flags=cv2.CALIB_FIX_K3
    )
    dist = dist.ravel().tolist()
    print(
        json.dumps(
            {
                "fx": k[0, 0],
                "fy": k[1, 1],
                "cx": k[0, 2],
                "cy": k[1, 2],
                "dist": (dist + [0.0] * 5)[:5],
                "rms_px": rms,
                "rvecs": [r.ravel().tolist() for r in rvecs],
                "tvecs": [t.ravel().tolist() for t in tvecs],
            }
        )
    )


def main():
    if len(sys.argv) != 5 or sys.argv[1] != "calibrate":
        sys.exit(__doc__)
    calibrate(sys.argv[2], int(sys.argv[3]), int(sys.argv[4]))


if __name__ == "__main__":
    main()
