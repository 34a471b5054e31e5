"""CrackSeg: a small encoder-decoder that predicts a crack probability map at half the input resolution.

Input `images` [1,3,S,S] RGB in [0,1] (the letterbox contract of MODEL_CARD.md), normalised inside the graph.
Output `crack_map` [1,1,S/2,S/2]: the probability that the 2x2 canvas cell holds a crack pixel (sigmoid inside).
"""
from __future__ import annotations

import torch
import torch.nn as nn
import torch.nn.functional as F

MEAN = 0.45
STD = 0.25
OUTPUT_STRIDE = 2


def conv(cin, cout, k=3, s=1, d=1):
    p = d * (k // 2)
    return nn.Sequential(nn.Conv2d(cin, cout, k, s, p, dilation=d, bias=False), nn.BatchNorm2d(cout),
                         nn.ReLU(inplace=True))


class PoolContext(nn.Module):
    """Cheap global context at the coarsest level: chained 5x5 max-pools (as SPPF), then a 1x1 mix."""

    def __init__(self, c):
        super().__init__()
        self.reduce = conv(c, c // 2, 1)
        self.mix = conv(c // 2 * 4, c, 1)
        self.pool = nn.MaxPool2d(5, 1, 2)

    def forward(self, x):
        x = self.reduce(x)
        a = self.pool(x)
        b = self.pool(a)
        c = self.pool(b)
        return self.mix(torch.cat([x, a, b, c], 1))


class CrackSeg(nn.Module):
    def __init__(self, ch=(16, 24, 48, 80, 112), dec=(16, 24, 32, 48)):
        super().__init__()
        c1, c2, c3, c4, c5 = ch
        d1, d2, d3, d4 = dec
        self.e1 = conv(3, c1, 3, 2)                                           # /2
        self.e2 = nn.Sequential(conv(c1, c2, 3, 2), conv(c2, c2))               # /4
        self.e3 = nn.Sequential(conv(c2, c3, 3, 2), conv(c3, c3))               # /8
        self.e4 = nn.Sequential(conv(c3, c4, 3, 2), conv(c4, c4), conv(c4, c4, d=2))  # /16
        self.e5 = nn.Sequential(conv(c4, c5, 3, 2), conv(c5, c5), PoolContext(c5))    # /32
        self.l5 = conv(c5, d4, 1)
        self.l4 = conv(c4, d4, 1)
        self.f4 = conv(d4, d4)
        self.u4 = conv(d4, d3, 1)
        self.l3 = conv(c3, d3, 1)
        self.f3 = conv(d3, d3)
        self.u3 = conv(d3, d2, 1)
        self.l2 = conv(c2, d2, 1)
        self.f2 = conv(d2, d2)
        self.u2 = conv(d2, d1, 1)
        self.l1 = conv(c1, d1, 1)
        self.f1 = conv(d1, d1)
        self.out = nn.Conv2d(d1, 1, 1)
        nn.init.normal_(self.out.weight, std=0.01)
        nn.init.constant_(self.out.bias, -4.0)

    @staticmethod
    def up(x):
        return F.interpolate(x, scale_factor=2.0, mode="nearest")

    def logits(self, x):
        """x: [B,3,S,S] in [0,1] -> crack logits [B,1,S/2,S/2]."""
        x = (x - MEAN) / STD
        x1 = self.e1(x)
        x2 = self.e2(x1)
        x3 = self.e3(x2)
        x4 = self.e4(x3)
        x5 = self.e5(x4)
        y = self.f4(self.l4(x4) + self.up(self.l5(x5)))
        y = self.f3(self.l3(x3) + self.up(self.u4(y)))
        y = self.f2(self.l2(x2) + self.up(self.u3(y)))
        y = self.f1(self.l1(x1) + self.up(self.u2(y)))
        return self.out(y)

    def forward(self, x):
        """Export path: [1,3,S,S] -> crack_map [1,1,S/2,S/2] in [0,1]."""
        return torch.sigmoid(self.logits(x))
