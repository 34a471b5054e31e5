"""The crack-detector pre/post-processing contract, in plain numpy (+ scipy for the components).

This is the reference implementation of what the Rust inference side does (see MODEL_CARD.md,
crates/vision/src/preprocess.rs and crates/vision/src/crack_map.rs). It is used by train.py (model selection),
eval.py and make_reference.py.
"""
from __future__ import annotations

import numpy as np

from scipy import ndimage

DEFAULT_SIZE = 320
PAD_VALUE = 0.5
STRIDE = 2                 # canvas pixels per crack-map cell
MAP_THRESHOLD = 0.5        # a cell at or above is a crack cell
MAX_DETECTIONS = 100
MIN_AREA_FRACTION = 0.001  # the dataset rule: boxes under 0.1% of the image are dropped
DILATION_FRACTION = 0.02   # the dataset rule: dilation radius round(0.02 * max(W, H)) image px
FULL_LENGTH_FRACTION = 0.5  # a component whose box diagonal is at least this fraction of max(W, H) ranks in full


def component_score(mean_p: float, box_diag: float, w: int, h: int) -> float:
    """0.5 + 0.5 * (mean probability of the crack cells) * min(1, diag / (0.5 * max(W, H)))^0.5.

    Ranks long, confident components first (chosen on the photos' train split over the cells' max,
    `analysis/linking.py`) and stays in [0.5, 1]: every component passes a threshold below 0.5 as before.
    """
    f = min(1.0, box_diag / (FULL_LENGTH_FRACTION * max(w, h))) ** 0.5
    return 0.5 + 0.5 * mean_p * f


def letterbox_params(w: int, h: int, size: int = DEFAULT_SIZE):
    """s = S / max(W, H); nw, nh = max(1, floor(W*s + 0.5)), max(1, floor(H*s + 0.5))."""
    s = np.float64(size) / np.float64(max(w, h))
    nw = max(1, int(np.floor(w * s + 0.5)))
    nh = max(1, int(np.floor(h * s + 0.5)))
    return float(s), nw, nh


def resize_bilinear(img: np.ndarray, nw: int, nh: int) -> np.ndarray:
    """Half-pixel-centre bilinear resize without antialiasing; uint8 HxWx3 -> float32 nh x nw x 3 on 0..255."""
    h, w = img.shape[:2]
    src = img.astype(np.float32)
    ox = np.arange(nw, dtype=np.float32)
    oy = np.arange(nh, dtype=np.float32)
    sx = (ox + np.float32(0.5)) * np.float32(w) / np.float32(nw) - np.float32(0.5)
    sy = (oy + np.float32(0.5)) * np.float32(h) / np.float32(nh) - np.float32(0.5)
    sx = np.clip(sx, 0, w - 1).astype(np.float32)
    sy = np.clip(sy, 0, h - 1).astype(np.float32)
    x0 = np.floor(sx).astype(np.int64)
    y0 = np.floor(sy).astype(np.int64)
    x1 = np.minimum(x0 + 1, w - 1)
    y1 = np.minimum(y0 + 1, h - 1)
    fx = (sx - x0.astype(np.float32))[None, :, None]
    fy = (sy - y0.astype(np.float32))[:, None, None]
    one = np.float32(1.0)
    top = (one - fx) * src[y0][:, x0] + fx * src[y0][:, x1]
    bot = (one - fx) * src[y1][:, x0] + fx * src[y1][:, x1]
    return ((one - fy) * top + fy * bot).astype(np.float32)


def letterbox(img: np.ndarray, size: int = DEFAULT_SIZE):
    """RGB8 image (H, W, 3) -> (tensor [1,3,S,S] float32 in [0,1], s).

    The resized image sits at the top-left of an SxS canvas filled with 0.5.
    """
    assert img.ndim == 3 and img.shape[2] == 3 and img.dtype == np.uint8
    h, w = img.shape[:2]
    s, nw, nh = letterbox_params(w, h, size)
    resized = resize_bilinear(img, nw, nh) / np.float32(255.0)
    canvas = np.full((size, size, 3), PAD_VALUE, dtype=np.float32)
    canvas[:nh, :nw] = resized
    return np.ascontiguousarray(canvas.transpose(2, 0, 1)[None]), s


def dilation_radius_cells(w: int, h: int, s: float) -> int:
    r_img = int(np.floor(DILATION_FRACTION * max(w, h) + 0.5))
    return max(1, int(np.floor(r_img * s / STRIDE + 0.5)))


def disk(r: int) -> np.ndarray:
    y, x = np.mgrid[-r:r + 1, -r:r + 1]
    return (x * x + y * y) <= r * r


def valid_cells(size: int, nw: int, nh: int):
    """Map cells that overlap the letterboxed image: rows < ceil(nh/2), cols < ceil(nw/2)."""
    return (nh + STRIDE - 1) // STRIDE, (nw + STRIDE - 1) // STRIDE


def map_to_detections(prob: np.ndarray, w: int, h: int, size: int, threshold: float = MAP_THRESHOLD,
                      max_det: int = MAX_DETECTIONS):
    """prob: [S/2, S/2] crack map of the letterboxed image -> list of (x0, y0, x1, y1, score), best first."""
    prob = np.asarray(prob, dtype=np.float32).reshape(size // STRIDE, size // STRIDE)
    s, nw, nh = letterbox_params(w, h, size)
    vr, vc = valid_cells(size, nw, nh)
    p = prob[:vr, :vc]
    b = p >= np.float32(threshold)
    if not b.any():
        return []
    r = dilation_radius_cells(w, h, s)
    dil = ndimage.binary_dilation(b, structure=disk(r))
    labels, n = ndimage.label(dil, structure=np.ones((3, 3), dtype=bool))
    out = []
    min_area = MIN_AREA_FRACTION * w * h
    for k in range(1, n + 1):
        cells = b & (labels == k)
        rows, cols = np.nonzero(cells)
        if len(rows) == 0:
            continue
        x0 = min(STRIDE * cols.min() / s, w)
        y0 = min(STRIDE * rows.min() / s, h)
        x1 = min(STRIDE * (cols.max() + 1) / s, w)
        y1 = min(STRIDE * (rows.max() + 1) / s, h)
        if (x1 - x0) * (y1 - y0) < min_area:
            continue
        score = component_score(float(p[cells].astype(np.float64).mean()), float(np.hypot(x1 - x0, y1 - y0)), w, h)
        out.append((float(x0), float(y0), float(x1), float(y1), score))
    order = sorted(range(len(out)), key=lambda i: -out[i][4])  # stable: ties keep raster order
    return [out[i] for i in order[:max_det]]


def map_to_image(prob: np.ndarray, w: int, h: int, size: int) -> np.ndarray:
    """The crack map at image resolution (nearest cell of each pixel centre): [H, W] float32."""
    prob = np.asarray(prob, dtype=np.float32).reshape(size // STRIDE, size // STRIDE)
    s, _, _ = letterbox_params(w, h, size)
    cx = np.minimum(np.floor((np.arange(w) + 0.5) * s / STRIDE).astype(np.int64), size // STRIDE - 1)
    cy = np.minimum(np.floor((np.arange(h) + 0.5) * s / STRIDE).astype(np.int64), size // STRIDE - 1)
    return prob[cy][:, cx]
