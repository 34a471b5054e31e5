"""Merges a trained box head (analysis/box_head.py) into the crack-map model: one ONNX graph, one run.

The merged model keeps the input `images` and the output `crack_map` of the model it was made from, and adds
`box_heat` [1, 1, S/8, S/8] (the probability that a box of the photos' kind is centred in the cell) and `box_reg`
[1, 4, S/8, S/8] (log width and log height in cells, the centre's offset in its cell). This checks that the
merged graph gives the crack map of the original exactly and the probe's boxes, evaluates the rule's boxes
followed by the head's on the photos' val splits (pycocotools), and times both graphs on one thread.
The shipped models are made this way (train.sh); crates/vision decodes the new outputs (`box_head.rs`) as
contract.head_to_detections does.

  python analysis/merge_box_head.py --head analysis/box_head_weights/box_head-32.pt --channels 32 --out /tmp/m.onnx
  python analysis/merge_box_head.py --model crack-detector-256.onnx --size 256 --head … --channels 32 \
      --out crack-detector-256.onnx --skip-eval      # in place, no val evaluation or timing
"""
from __future__ import annotations

import argparse
import io
import os
import sys
import time

import numpy as np
import onnx
import torch
import torch.nn as nn
from onnx import compose

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import box_head as bh  # noqa: E402

HERE = bh.HERE


class HeadOnMaps(nn.Module):
    """The head with its input stacking (box_head.stack_inputs) inside, probabilities out."""

    def __init__(self, head: bh.BoxHead):
        super().__init__()
        self.head = head

    def forward(self, crack_map, f8, deep):
        logit, reg = self.head(bh.stack_inputs(crack_map, f8, deep))
        return torch.sigmoid(logit), reg


def merged_model(tapped, head: bh.BoxHead, size: int) -> onnx.ModelProto:
    """The tapped crack-map model (box_head.tapped_model's answer) with the head on its taps."""
    raw, names, channels = tapped
    base = onnx.load_from_string(raw)
    n8, cells = size // bh.HEAD_STRIDE, size // 2
    deep_side = [d.dim_value for d in base.graph.output[-1].type.tensor_type.shape.dim][-1]
    args = (torch.zeros(1, 1, cells, cells), torch.zeros(1, channels[0], n8, n8),
            torch.zeros(1, channels[1], deep_side, deep_side))
    buf = io.BytesIO()
    opset = max(o.version for o in base.opset_import if o.domain in ("", "ai.onnx"))
    torch.onnx.export(HeadOnMaps(head).eval(), args, buf, input_names=["crack_map", "f8", "deep"],
                      output_names=["box_heat", "box_reg"], opset_version=opset, dynamo=False)
    part = onnx.load_from_string(buf.getvalue())
    part.ir_version = base.ir_version
    part = compose.add_prefix(part, "box_head/")
    io_map = [("crack_map", "box_head/crack_map"), (names[0], "box_head/f8"), (names[1], "box_head/deep")]
    new_outputs = ("box_head/box_heat", "box_head/box_reg")
    merged = compose.merge_models(base, part, io_map=io_map, outputs=["crack_map", *new_outputs])
    for node in merged.graph.node:
        node.output[:] = [o.removeprefix("box_head/") if o in new_outputs else o for o in node.output]
    for out in merged.graph.output:
        out.name = out.name.removeprefix("box_head/")
    onnx.checker.check_model(merged)
    return merged


def median_ms(sess, feeds, runs=200):
    for _ in range(20):
        sess.run(None, feeds)
    ts = []
    for _ in range(runs):
        t0 = time.perf_counter()
        sess.run(None, feeds)
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts) * 1e3)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model", default=os.path.join(HERE, "crack-detector-320.onnx"))
    ap.add_argument("--size", type=int, default=320)
    ap.add_argument("--head", required=True, help="box_head.pt written by box_head.py --out")
    ap.add_argument("--channels", type=int, default=64)
    ap.add_argument("--out", required=True, help="where to write the merged ONNX model (may be --model itself)")
    ap.add_argument("--skip-eval", action="store_true", help="only the crack-map check: no val boxes, no timing")
    a = ap.parse_args()
    torch.set_num_threads(1)
    base_raw = open(a.model, "rb").read()
    if any(o.name == "box_heat" for o in onnx.load_from_string(base_raw).graph.output):
        sys.exit(f"{a.model} already has a box head (output `box_heat`): merge into the crack-map model alone")
    tapped = bh.tapped_model(a.model, a.size)
    head = bh.BoxHead(sum(tapped[2]) + 2, a.channels)
    head.load_state_dict(torch.load(a.head))
    head.eval()
    merged = merged_model(tapped, head, a.size)
    onnx.save(merged, a.out)
    merged_raw = merged.SerializeToString()
    sess, base = bh.session(merged_raw, 2), bh.session(base_raw, 2)

    def run_merged(img):
        """box_head.evaluate's features: the crack map, and the head's two outputs where it wants f8 and deep."""
        x, s = bh.contract.letterbox(img, a.size)
        cmap, heat, reg = sess.run(["crack_map", "box_heat", "box_reg"], {"images": x})
        return cmap[0, 0], torch.from_numpy(heat[0, 0]), torch.from_numpy(reg), s

    run_merged.size = a.size
    val = bh.load_split("val")
    worst = 0.0
    for _ds, _iid, img, _boxes in val[:: max(1, len(val) // 10)]:
        x, _ = bh.contract.letterbox(img, a.size)
        worst = max(worst, float(np.abs(sess.run(["crack_map"], {"images": x})[0]
                                        - base.run(["crack_map"], {"images": x})[0]).max()))
    print(f"merged: {a.out}, outputs {[o.name for o in merged.graph.output]}; "
          f"crack map against the original, largest difference on 10 val photos: {worst:.2e}")
    if worst > 0.0:
        sys.exit("the merged graph changed the crack map: not a model to ship")
    if a.skip_eval:
        return
    print(bh.fmt(bh.evaluate(head, run_merged, val,
                             boxes_of=lambda _cmap, heat, reg, s, w, h: bh.decode_maps(heat, reg, s, w, h))))
    x = np.zeros((1, 3, a.size, a.size), np.float32)
    t_m = median_ms(bh.session(merged_raw, 1), {"images": x})
    t_b = median_ms(bh.session(base_raw, 1), {"images": x})
    print(f"one thread, median of 200: original {t_b:.2f} ms, merged {t_m:.2f} ms ({t_m / t_b:.2f}x)")


if __name__ == "__main__":
    main()
