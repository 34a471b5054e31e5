"""The crack-detector pre/post-processing contract, in plain numpy.

This is the reference implementation of what the Rust inference side does (see MODEL_CARD.md).
It is used by eval.py and make_reference.py; training uses its own augmentation pipeline.
"""
from __future__ import annotations

import numpy as np

DEFAULT_SIZE = 320
PAD_VALUE = 0.5
DETECT_THRESHOLD = 0.25
EVAL_THRESHOLD = 0.001
NMS_IOU = 0.5
MAX_DETECTIONS = 100


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


def box_iou_one(box: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    ix0 = np.maximum(box[0], boxes[:, 0])
    iy0 = np.maximum(box[1], boxes[:, 1])
    ix1 = np.minimum(box[2], boxes[:, 2])
    iy1 = np.minimum(box[3], boxes[:, 3])
    inter = np.clip(ix1 - ix0, 0, None) * np.clip(iy1 - iy0, 0, None)
    a = max(box[2] - box[0], 0) * max(box[3] - box[1], 0)
    b = np.clip(boxes[:, 2] - boxes[:, 0], 0, None) * np.clip(boxes[:, 3] - boxes[:, 1], 0, None)
    union = a + b - inter
    return np.where(union > 0, inter / np.maximum(union, 1e-12), 0.0)


def nms(boxes: np.ndarray, scores: np.ndarray, iou: float = NMS_IOU, max_det: int = MAX_DETECTIONS) -> np.ndarray:
    """Class-agnostic greedy NMS; stable sort by score descending. Returns kept indices."""
    order = np.argsort(-scores, kind="stable")
    keep = []
    suppressed = np.zeros(len(order), dtype=bool)
    for i_pos, i in enumerate(order):
        if suppressed[i_pos]:
            continue
        keep.append(i)
        if len(keep) >= max_det:
            break
        rest = order[i_pos + 1:]
        if len(rest) == 0:
            break
        ious = box_iou_one(boxes[i], boxes[rest])
        suppressed[i_pos + 1:] |= ious > iou
    return np.array(keep, dtype=np.int64)


def postprocess(detections: np.ndarray, s: float, w: int, h: int, threshold: float = DETECT_THRESHOLD,
                iou: float = NMS_IOU, max_det: int = MAX_DETECTIONS):
    """Raw model output [1,N,5] (canvas pixels) -> list of (x0, y0, x1, y1, score) in image pixels."""
    d = np.asarray(detections, dtype=np.float32).reshape(-1, 5)
    d = d[d[:, 4] >= threshold]
    boxes = d[:, :4].astype(np.float64) / s
    boxes[:, [0, 2]] = np.clip(boxes[:, [0, 2]], 0, w)
    boxes[:, [1, 3]] = np.clip(boxes[:, [1, 3]], 0, h)
    scores = d[:, 4].astype(np.float64)
    keep = nms(boxes, scores, iou, max_det)
    return [(float(b[0]), float(b[1]), float(b[2]), float(b[3]), float(sc)) for b, sc in zip(boxes[keep], scores[keep])]
