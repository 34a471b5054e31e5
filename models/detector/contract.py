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
HEAD_STRIDE = 8            # canvas pixels per cell of the box head's outputs (box_heat, box_reg)
HEAD_MIN_PROBABILITY = 0.02  # a box head peak below this is no box
HEAD_SCORE_SCALE = 0.5     # a box head box scores HEAD_SCORE_SCALE * p: in [0, 0.5), below every component


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


def head_to_detections(heat: np.ndarray, reg: np.ndarray, w: int, h: int, size: int,
                       max_det: int = MAX_DETECTIONS):
    """The box head's boxes (models with `box_heat` [1,1,S/8,S/8] and `box_reg` [1,4,S/8,S/8]) -> list of
    (x0, y0, x1, y1, score), best first.

    One box per cell whose probability p is at least HEAD_MIN_PROBABILITY and the largest of its 3x3
    neighbourhood (ties included; cells outside the map do not count); best p first, ties in raster order; at most
    max_det. The box: centre (c + reg[2], r + reg[3]) cells, width exp(reg[0]) and height exp(reg[1]) cells, times
    HEAD_STRIDE / s image pixels, clipped to the image; empty boxes dropped. Score HEAD_SCORE_SCALE * p.
    """
    n = size // HEAD_STRIDE
    p = np.asarray(heat, dtype=np.float32).reshape(n, n)
    reg = np.asarray(reg, dtype=np.float32).reshape(4, n, n)
    s, _, _ = letterbox_params(w, h, size)
    padded = np.pad(p, 1, constant_values=-np.inf)
    neighbourhood = np.max([padded[dy:dy + n, dx:dx + n] for dy in range(3) for dx in range(3)], axis=0)
    rows, cols = np.nonzero((p == neighbourhood) & (p >= np.float32(HEAD_MIN_PROBABILITY)))
    order = np.argsort(-p[rows, cols], kind="stable")[:max_det]
    f = HEAD_STRIDE / s
    out = []
    for k in order:
        r, c = rows[k], cols[k]
        bw, bh = float(np.exp(np.float64(reg[0, r, c]))), float(np.exp(np.float64(reg[1, r, c])))
        cx, cy = c + float(reg[2, r, c]), r + float(reg[3, r, c])
        x0, y0 = max((cx - bw / 2) * f, 0.0), max((cy - bh / 2) * f, 0.0)
        x1, y1 = min((cx + bw / 2) * f, float(w)), min((cy + bh / 2) * f, float(h))
        if x1 > x0 and y1 > y0:
            out.append((x0, y0, x1, y1, HEAD_SCORE_SCALE * float(p[r, c])))
    return out


def detections(outputs: dict, w: int, h: int, size: int, max_det: int = MAX_DETECTIONS):
    """Every detection of a model's outputs (name -> array): the crack map's components by the rule, then, for a
    model with a box head, the head's boxes below them (scores < 0.5 <= every component's); at most max_det."""
    out = map_to_detections(outputs["crack_map"], w, h, size, max_det=max_det)
    if "box_heat" in outputs and "box_reg" in outputs:
        out += head_to_detections(outputs["box_heat"], outputs["box_reg"], w, h, size, max_det)
    return out[:max_det]


def map_to_image(prob: np.ndarray, w: int, h: int, size: int) -> np.ndarray:
    """The crack map at image resolution (nearest cell of each pixel centre): [H, W] float32."""
    prob = np.asarray(prob, dtype=np.float32).reshape(size // STRIDE, size // STRIDE)
    s, _, _ = letterbox_params(w, h, size)
    cx = np.minimum(np.floor((np.arange(w) + 0.5) * s / STRIDE).astype(np.int64), size // STRIDE - 1)
    cy = np.minimum(np.floor((np.arange(h) + 0.5) * s / STRIDE).astype(np.int64), size // STRIDE - 1)
    return prob[cy][:, cx]
