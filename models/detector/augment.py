"""Paper-style augmentation (visual-tactile crack localisation, Sec. II-A), numpy + PIL only.

A sample is either a plain image with its own boxes, or a composite: a crack-free background (a crack-free
region of a photo, or a procedural concrete texture) with 1-2 crack patches (crops around GT boxes) and a
crack-free patch pasted at random. 1-2 procedurally drawn screws are added to both kinds. Then HSV jitter,
horizontal flip, scale, translate, rotate and shear; boxes are transformed by their corners (enclosing box,
clipped; boxes mostly outside are dropped). The output is an SxS canvas laid out like the inference letterbox
(image at the top-left, 0.5 grey elsewhere) when no geometric jitter is applied.
"""
from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass

import numpy as np
from PIL import Image, ImageDraw, ImageFilter

PAD = (128, 128, 128)


@dataclass
class Photo:
    img: np.ndarray          # HxWx3 uint8
    boxes: np.ndarray        # Kx4 float (x0,y0,x1,y1)
    mask: np.ndarray | None  # HxW bool or None
    dataset: str
    file_name: str


def load_photos(coco_path: str, root: str) -> list[Photo]:
    with open(coco_path) as f:
        coco = json.load(f)
    by_img: dict[int, list] = {}
    for a in coco["annotations"]:
        x, y, w, h = a["bbox"]
        by_img.setdefault(a["image_id"], []).append([x, y, x + w, y + h])
    photos = []
    for im in coco["images"]:
        img = np.asarray(Image.open(os.path.join(root, im["file_name"])).convert("RGB"))
        mask = None
        mf = im.get("mask_file")
        if mf:
            # mask_file is relative to the merged root (<ds>/masks/...); try both roots
            cand = [os.path.join(root, mf), os.path.join(root, "..", mf), os.path.join(root, mf.split("/", 1)[1])]
            for c in cand:
                if os.path.exists(c):
                    mask = np.asarray(Image.open(c).convert("L")) > 0
                    break
        photos.append(Photo(img, np.array(by_img.get(im["id"], []), dtype=np.float64).reshape(-1, 4), mask,
                            im.get("dataset", ""), im["file_name"]))
    return photos


# ----------------------------------------------------------------------------------------------------------
# procedural pieces

def concrete_texture(rng: np.random.Generator, w: int, h: int) -> np.ndarray:
    acc = np.zeros((h, w), np.float32)
    amp, tot = 1.0, 0.0
    for cells in (3, 6, 12, 24, 48, 96):
        g = rng.random((cells, cells)).astype(np.float32)
        up = np.asarray(Image.fromarray((g * 255).astype(np.uint8)).resize((w, h), Image.BILINEAR), np.float32) / 255
        acc += amp * up
        tot += amp
        amp *= rng.uniform(0.5, 0.8)
    acc /= tot
    acc = (acc - acc.mean()) * rng.uniform(0.6, 2.0)
    acc += rng.normal(0, rng.uniform(0.01, 0.06), (h, w)).astype(np.float32)  # fine grain
    # speckles (aggregate / pores)
    n = int(w * h * rng.uniform(0.0005, 0.006))
    ys, xs = rng.integers(0, h, n), rng.integers(0, w, n)
    acc[ys, xs] += rng.choice([-1, 1], n) * rng.uniform(0.1, 0.35, n)
    grey = rng.uniform(0.3, 0.8)
    tint = 1 + rng.normal(0, 0.04, 3)
    img = (grey + acc * 0.35)[..., None] * tint[None, None]
    img = np.clip(img * 255, 0, 255).astype(np.uint8)
    if rng.random() < 0.5:
        img = np.asarray(Image.fromarray(img).filter(ImageFilter.GaussianBlur(rng.uniform(0.3, 1.2))))
    return img


def draw_screw(rng: np.random.Generator, im: Image.Image):
    w, h = im.size
    r = max(4, int(min(w, h) * rng.uniform(0.03, 0.08)))
    cx, cy = rng.integers(0, w), rng.integers(0, h)
    ss = 4  # supersample
    size = 2 * r + 4
    big = Image.new("RGBA", (size * ss, size * ss), (0, 0, 0, 0))
    d = ImageDraw.Draw(big)
    base = rng.uniform(110, 210)
    tint = rng.normal(0, 6, 3)
    c = size * ss / 2
    R = r * ss
    # shaded disc: concentric rings, lighter towards a highlight offset
    hx, hy = c - R * 0.3, c - R * 0.3
    steps = 12
    for k in range(steps, 0, -1):
        rr = R * k / steps
        v = base * (0.65 + 0.5 * (1 - k / steps))
        col = tuple(int(np.clip(v + t, 0, 255)) for t in tint)
        ox = (hx - c) * (1 - k / steps)
        oy = (hy - c) * (1 - k / steps)
        d.ellipse([c - rr + ox, c - rr + oy, c + rr + ox, c + rr + oy], fill=col + (255,))
    d.ellipse([c - R, c - R, c + R, c + R], outline=(int(base * 0.4),) * 3 + (255,), width=max(1, ss))
    # slot or cross
    ang = rng.uniform(0, math.pi)
    sw = max(2, int(R * 0.18))
    dark = (int(base * 0.25),) * 3 + (255,)
    for a in ([ang] if rng.random() < 0.5 else [ang, ang + math.pi / 2]):
        dx, dy = math.cos(a) * R * 0.7, math.sin(a) * R * 0.7
        d.line([c - dx, c - dy, c + dx, c + dy], fill=dark, width=sw)
    small = big.resize((size, size), Image.LANCZOS)
    # soft shadow
    sh = Image.new("RGBA", (size, size), (0, 0, 0, 0))
    ImageDraw.Draw(sh).ellipse([2, 2, size - 1, size - 1], fill=(0, 0, 0, 90))
    sh = sh.filter(ImageFilter.GaussianBlur(1.5))
    im.paste(sh, (int(cx - size / 2 + 2), int(cy - size / 2 + 2)), sh)
    im.paste(small, (int(cx - size / 2), int(cy - size / 2)), small)


# ----------------------------------------------------------------------------------------------------------

def box_overlaps(b, boxes, margin=0.0):
    if len(boxes) == 0:
        return False
    return bool(np.any((boxes[:, 0] - margin < b[2]) & (boxes[:, 2] + margin > b[0]) &
                       (boxes[:, 1] - margin < b[3]) & (boxes[:, 3] + margin > b[1])))


class Augmenter:
    def __init__(self, photos: list[Photo], size: int = 320, p_plain: float = 0.35, p_procedural_bg: float = 0.4,
                 geo: bool = True):
        self.photos = photos
        self.size = size
        self.p_plain = p_plain
        self.p_proc = p_procedural_bg
        self.geo = geo
        self.crack_refs = [(i, j) for i, p in enumerate(photos) for j in range(len(p.boxes))]

    # crack-free crop of a photo: away from GT boxes (and from mask pixels, which lie inside boxes)
    def crack_free_crop(self, rng, min_frac=0.2, max_frac=0.6):
        for _ in range(30):
            p = self.photos[rng.integers(len(self.photos))]
            h, w = p.img.shape[:2]
            cw = int(w * rng.uniform(min_frac, max_frac))
            ch = int(h * rng.uniform(min_frac, max_frac))
            if cw < 16 or ch < 16:
                continue
            x0, y0 = rng.integers(0, w - cw + 1), rng.integers(0, h - ch + 1)
            b = (x0, y0, x0 + cw, y0 + ch)
            if box_overlaps(b, p.boxes, margin=6):
                continue
            if p.mask is not None and p.mask[y0:y0 + ch, x0:x0 + cw].any():
                continue
            return p.img[y0:y0 + ch, x0:x0 + cw]
        return None

    def background(self, rng, bw, bh):
        if rng.random() >= self.p_proc:
            crop = self.crack_free_crop(rng, 0.2, 0.6)
            if crop is not None:
                return np.asarray(Image.fromarray(crop).resize((bw, bh), Image.BILINEAR))
        return concrete_texture(rng, bw, bh)

    def composite(self, rng):
        bw = int(rng.uniform(320, 640))
        bh = int(bw * rng.uniform(0.6, 1.4))
        bg = Image.fromarray(self.background(rng, bw, bh))
        boxes = []
        ncr = 1 if rng.random() < 0.6 else 2
        for _ in range(ncr):
            pi, bj = self.crack_refs[rng.integers(len(self.crack_refs))]
            p = self.photos[pi]
            h, w = p.img.shape[:2]
            x0, y0, x1, y1 = p.boxes[bj]
            m = rng.uniform(0.0, 0.15)
            mx, my = (x1 - x0) * m + 2, (y1 - y0) * m + 2
            cx0, cy0 = int(max(0, x0 - mx)), int(max(0, y0 - my))
            cx1, cy1 = int(min(w, math.ceil(x1 + mx))), int(min(h, math.ceil(y1 + my)))
            patch = p.img[cy0:cy1, cx0:cx1]
            # other GT boxes inside the patch become boxes too
            sub = []
            for b in p.boxes:
                ix0, iy0 = max(b[0], cx0), max(b[1], cy0)
                ix1, iy1 = min(b[2], cx1), min(b[3], cy1)
                if ix1 - ix0 > 2 and iy1 - iy0 > 2:
                    full = (b[2] - b[0]) * (b[3] - b[1])
                    if (ix1 - ix0) * (iy1 - iy0) > 0.5 * full:
                        sub.append([ix0 - cx0, iy0 - cy0, ix1 - cx0, iy1 - cy0])
            ph, pw = patch.shape[:2]
            sc = rng.uniform(0.5, 1.1) * (bw / max(w, h)) * 1.2
            sc = min(sc, 0.95 * bw / pw, 0.95 * bh / ph)
            nw, nh = max(4, int(pw * sc)), max(4, int(ph * sc))
            placed = False
            for _ in range(10):
                px, py = rng.integers(0, bw - nw + 1), rng.integers(0, bh - nh + 1)
                if not box_overlaps((px, py, px + nw, py + nh), np.array(boxes).reshape(-1, 4), margin=2):
                    placed = True
                    break
            if not placed:
                continue
            bg.paste(Image.fromarray(patch).resize((nw, nh), Image.BILINEAR), (int(px), int(py)))
            fx, fy = nw / pw, nh / ph
            for b in sub:
                boxes.append([px + b[0] * fx, py + b[1] * fy, px + b[2] * fx, py + b[3] * fy])
        # crack-free patch(es), not over the pasted cracks
        for _ in range(1 if rng.random() < 0.7 else 2):
            crop = self.crack_free_crop(rng, 0.15, 0.5)
            if crop is None:
                crop = concrete_texture(rng, int(rng.integers(40, 160)), int(rng.integers(40, 160)))
            ph, pw = crop.shape[:2]
            sc = rng.uniform(0.5, 1.5)
            nw, nh = int(min(bw * 0.6, max(16, pw * sc))), int(min(bh * 0.6, max(16, ph * sc)))
            for _ in range(10):
                px, py = rng.integers(0, bw - nw + 1), rng.integers(0, bh - nh + 1)
                if not box_overlaps((px, py, px + nw, py + nh), np.array(boxes).reshape(-1, 4)):
                    bg.paste(Image.fromarray(crop).resize((nw, nh), Image.BILINEAR), (int(px), int(py)))
                    break
        return bg, np.array(boxes, dtype=np.float64).reshape(-1, 4)

    def hsv_jitter(self, rng, im: Image.Image) -> Image.Image:
        hsv = np.asarray(im.convert("HSV")).astype(np.float32)
        hsv[..., 0] = (hsv[..., 0] + rng.uniform(-8, 8)) % 256
        hsv[..., 1] *= rng.uniform(0.5, 1.5)
        hsv[..., 2] *= rng.uniform(0.6, 1.4)
        return Image.fromarray(np.clip(hsv, 0, 255).astype(np.uint8), "HSV").convert("RGB")

    def sample(self, rng: np.random.Generator):
        """Returns (canvas uint8 SxSx3, boxes Kx4 float in canvas pixels)."""
        S = self.size
        if rng.random() < self.p_plain:
            p = self.photos[rng.integers(len(self.photos))]
            im, boxes = Image.fromarray(p.img), p.boxes.copy()
        else:
            im, boxes = self.composite(rng)
        for _ in range(rng.integers(1, 3)):
            draw_screw(rng, im)
        if rng.random() < 0.8:
            im = self.hsv_jitter(rng, im)
        W, H = im.size
        # affine: source -> canvas. Base = letterbox (scale S/max(W,H), top-left).
        s = S / max(W, H)
        A = np.array([[s, 0, 0], [0, s, 0], [0, 0, 1]], np.float64)
        if rng.random() < 0.5:  # horizontal flip of the source
            A = A @ np.array([[-1, 0, W], [0, 1, 0], [0, 0, 1]], np.float64)
        if self.geo and rng.random() < 0.8:
            sc = rng.uniform(0.6, 1.35)
            rot = math.radians(rng.uniform(-8, 8))
            sh = math.radians(rng.uniform(-5, 5))
            c = np.array([[1, 0, -W * s / 2], [0, 1, -H * s / 2], [0, 0, 1]])
            R = np.array([[math.cos(rot) * sc, -math.sin(rot) * sc, 0], [math.sin(rot) * sc, math.cos(rot) * sc, 0], [0, 0, 1]])
            Sh = np.array([[1, math.tan(sh), 0], [0, 1, 0], [0, 0, 1]])
            tx = rng.uniform(-0.2, 0.2) * S + W * s / 2
            ty = rng.uniform(-0.2, 0.2) * S + H * s / 2
            T = np.array([[1, 0, tx], [0, 1, ty], [0, 0, 1]])
            A = T @ Sh @ R @ c @ A
        Ai = np.linalg.inv(A)
        canvas = im.transform((S, S), Image.AFFINE, tuple(Ai[:2].reshape(-1)), resample=Image.BILINEAR, fillcolor=PAD)
        out = []
        for b in boxes:
            pts = np.array([[b[0], b[1], 1], [b[2], b[1], 1], [b[0], b[3], 1], [b[2], b[3], 1]]).T
            q = (A @ pts)[:2]
            x0, y0, x1, y1 = q[0].min(), q[1].min(), q[0].max(), q[1].max()
            area = (x1 - x0) * (y1 - y0)
            cx0, cy0, cx1, cy1 = max(0, x0), max(0, y0), min(S, x1), min(S, y1)
            if cx1 - cx0 < 4 or cy1 - cy0 < 4:
                continue
            if (cx1 - cx0) * (cy1 - cy0) < 0.4 * area:
                continue
            out.append([cx0, cy0, cx1, cy1])
        return np.asarray(canvas), np.array(out, dtype=np.float32).reshape(-1, 4)
