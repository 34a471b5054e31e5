"""Small anchor-free (FCOS-style) single-class crack detector, decoding inside the graph."""
from __future__ import annotations

import torch
import torch.nn as nn
import torch.nn.functional as F

MEAN = 0.45
STD = 0.25
STRIDES = (16, 32)


def conv(cin, cout, k=3, s=1):
    return nn.Sequential(nn.Conv2d(cin, cout, k, s, k // 2, bias=False), nn.BatchNorm2d(cout), nn.SiLU(inplace=True))


class SPPF(nn.Module):
    def __init__(self, c):
        super().__init__()
        self.cv1 = conv(c, c // 2, 1)
        self.cv2 = conv(c // 2 * 4, c, 1)
        self.pool = nn.MaxPool2d(5, 1, 2)

    def forward(self, x):
        x = self.cv1(x)
        y1 = self.pool(x)
        y2 = self.pool(y1)
        y3 = self.pool(y2)
        return self.cv2(torch.cat([x, y1, y2, y3], 1))


class CrackDet(nn.Module):
    def __init__(self, ch=(16, 32, 64, 96, 160), head=96):
        super().__init__()
        c1, c2, c3, c4, c5 = ch
        self.stem = conv(3, c1, 3, 2)                                       # /2
        self.s2 = nn.Sequential(conv(c1, c2, 3, 2), conv(c2, c2))             # /4
        self.s3 = nn.Sequential(conv(c2, c3, 3, 2), conv(c3, c3))             # /8
        self.s4 = nn.Sequential(conv(c3, c4, 3, 2), conv(c4, c4))             # /16
        self.s5 = nn.Sequential(conv(c4, c5, 3, 2), conv(c5, c5), SPPF(c5))   # /32
        self.lat5 = conv(c5, head, 1)
        self.lat4 = conv(c4, head, 1)
        self.fuse4 = conv(head, head)
        self.head = nn.Sequential(conv(head, head), conv(head, head))
        self.out = nn.Conv2d(head, 5, 1)
        self.scales = nn.Parameter(torch.zeros(len(STRIDES)))
        nn.init.normal_(self.out.weight, std=0.01)
        nn.init.constant_(self.out.bias, 0.0)
        with torch.no_grad():
            self.out.bias[0] = -4.6  # objectness prior 0.01

    def raw(self, x):
        """x: [B,3,S,S] in [0,1] -> list of per-level raw maps [B,5,h,w]."""
        x = (x - MEAN) / STD
        x = self.s3(self.s2(self.stem(x)))
        c4 = self.s4(x)
        c5 = self.s5(c4)
        p5 = self.lat5(c5)
        p4 = self.fuse4(self.lat4(c4) + F.interpolate(p5, scale_factor=2.0, mode="nearest"))
        return [self.out(self.head(p)) for p in (p4, p5)]

    @staticmethod
    def decode_level(r, stride, scale):
        """r: [B,5,h,w] -> (logits [B,hw], ltrb [B,hw,4] in px, centres [hw,2])."""
        b, _, h, w = r.shape
        r = r.flatten(2).transpose(1, 2)  # [B,hw,5]
        ys = (torch.arange(h, dtype=r.dtype) + 0.5) * stride
        xs = (torch.arange(w, dtype=r.dtype) + 0.5) * stride
        gy, gx = torch.meshgrid(ys, xs, indexing="ij")
        centres = torch.stack([gx.reshape(-1), gy.reshape(-1)], 1)
        ltrb = torch.exp(torch.clamp(r[..., 1:] * torch.exp(scale), max=6.0)) * stride
        return r[..., 0], ltrb, centres

    def decoded(self, x):
        outs = []
        for i, (r, st) in enumerate(zip(self.raw(x), STRIDES)):
            outs.append(self.decode_level(r, st, self.scales[i]))
        return outs

    def forward(self, x):
        """Export path: [1,3,S,S] -> detections [1,N,5] = x0,y0,x1,y1 (canvas px), score."""
        rows = []
        for logit, ltrb, c in self.decoded(x):
            boxes = torch.cat([c[None] - ltrb[..., :2], c[None] + ltrb[..., 2:]], -1)
            rows.append(torch.cat([boxes, torch.sigmoid(logit)[..., None]], -1))
        return torch.cat(rows, 1)


def num_outputs(size: int) -> int:
    return sum((size // s) ** 2 for s in STRIDES)
