#!/usr/bin/env python3
"""Trains the denoiser network (render/denoise.h, DenoiseWithNetwork) on frames from make_data.py
and writes it as ONNX for OpenCV's dnn module: render/models/denoiser.onnx, with its provenance in
render/models/denoiser.json.

    PYTHONPATH=build/python python3 tools/denoiser/make_data.py --out /tmp/denoiser_data
    python3 tools/denoiser/train.py --data /tmp/denoiser_data --minutes 25

The network: a U-Net whose levels are 1/2, 1/4 and 1/8 of the image (2 x 2 strided convolutions
down, transposed ones up, a 3 x 3 convolution and ReLU at each level, skip connections), and a
full-resolution 3 x 3 convolution that sees the input features again, so that edges of the
normals, depth and albedo stay sharp. Input and output: tools/denoiser/features.py.

The network gives four channels: its own estimate of the light and a weight that blends it with
the noisy input's (so that where the input is already clean it can pass it on). The loss is the
squared error of the displayed values (filmic, sRGB, as the benchmark measures) against the target
render's; the parts' pixels count twice, as users train on them. A squared error's minimiser is
the target's mean, so targets of 64 samples serve nearly as well as clean ones (Noise2Noise; the
display transform's curvature biases the mean by about 0.2 sigma^2, under 1 % at 64 samples).
"""
import argparse
import datetime
import glob
import json
import os
import random
import sys
import time

import numpy as np
import torch
import torch.nn as nn

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
import features as F  # noqa: E402


class Net(nn.Module):
    def __init__(self, widths=(24, 48, 64), head=16, skips="concat"):
        super().__init__()
        a, b, c = widths
        if skips not in ("concat", "add"):
            raise ValueError(f"skips: '{skips}' is neither 'concat' nor 'add'")
        self.add = skips == "add"
        m = 1 if self.add else 2  # a decoder level reads its skip added, or concatenated

        def relu():
            return nn.ReLU(inplace=True)

        cin = F.CHANNELS
        self.down0 = nn.Sequential(nn.Conv2d(cin, a, 2, stride=2), relu(),
                                   nn.Conv2d(a, a, 3, padding=1), relu())
        self.down1 = nn.Sequential(nn.Conv2d(a, b, 2, stride=2), relu(),
                                   nn.Conv2d(b, b, 3, padding=1), relu())
        self.down2 = nn.Sequential(nn.Conv2d(b, c, 2, stride=2), relu(),
                                   nn.Conv2d(c, c, 3, padding=1), relu())
        self.up2 = nn.Sequential(nn.ConvTranspose2d(c, b, 2, stride=2), relu())
        self.dec1 = nn.Sequential(nn.Conv2d(m * b, b, 3, padding=1), relu())
        self.up1 = nn.Sequential(nn.ConvTranspose2d(b, a, 2, stride=2), relu())
        self.dec0 = nn.Sequential(nn.Conv2d(m * a, a, 3, padding=1), relu())
        self.up0 = nn.Sequential(nn.ConvTranspose2d(a, head, 2, stride=2), relu())
        self.full = nn.Sequential(nn.Conv2d(head + cin, head, 3, padding=1), relu(),
                                  nn.Conv2d(head, 4, 1))

    def join(self, up, skip):
        return up + skip if self.add else torch.cat([up, skip], 1)

    def forward(self, x):
        e0 = self.down0(x)
        e1 = self.down1(e0)
        e2 = self.down2(e1)
        d1 = self.dec1(self.join(self.up2(e2), e1))
        d0 = self.dec0(self.join(self.up1(d1), e0))
        return self.full(torch.cat([self.up0(d0), x], 1))


def display(x):
    """cadsynth's filmic display transform at exposure 0 (tools/bench/equal_error.py display)."""
    x = torch.clamp(x, min=0.0)
    x = torch.clamp(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0)
    return torch.where(x <= 0.0031308, 12.92 * x,
                       1.055 * torch.pow(torch.clamp(x, min=1e-8), 1 / 2.4) - 0.055)


class Frames:
    """The training frames, in memory, with each noisy level's frame scalars."""

    def __init__(self, paths):
        self.frames = []
        for path in paths:
            d = dict(np.load(path))
            levels = sorted(int(k.split("_")[1]) for k in d if k.startswith("radiance_"))
            frame = {k: d[k] for k in ("depth", "instance", "albedo", "normal", "target")}
            frame["name"] = os.path.basename(path)
            frame["levels"] = {}
            for s in levels:
                r = np.nan_to_num(d[f"radiance_{s}"].astype(np.float32), posinf=0.0)
                x, scale, _ = F.features(r, d["albedo"], d["normal"], d["depth"],
                                         d[f"variance_{s}"])
                frame["levels"][s] = (x.astype(np.float16), scale, r.astype(np.float16))
            self.frames.append(frame)

    def crop(self, rng, size, levels):
        frame = self.frames[rng.randrange(len(self.frames))]
        s = rng.choice([s for s in levels if s in frame["levels"]])
        x, scale, _ = frame["levels"][s]
        h, w = frame["depth"].shape
        parts = frame.get("_parts")
        if parts is None:
            parts = frame["_parts"] = np.argwhere(frame["instance"] > 0)
        if len(parts) and rng.random() < 0.7:
            v, u = parts[rng.randrange(len(parts))]
        else:
            v, u = rng.randrange(h), rng.randrange(w)
        v0 = int(np.clip(v - size // 2, 0, h - size))
        u0 = int(np.clip(u - size // 2, 0, w - size))
        sl = (slice(v0, v0 + size), slice(u0, u0 + size))
        hit = frame["depth"][sl] > 0
        a = np.where(hit[..., None], np.maximum(F.ALBEDO_FLOOR,
                                                 frame["albedo"][sl].astype(np.float32)), 1.0)
        weight = hit * (1.0 + (frame["instance"][sl] > 0))
        target = np.nan_to_num(frame["target"][sl].astype(np.float32), posinf=0.0)
        out = [x[:, sl[0], sl[1]].astype(np.float32), a.transpose(2, 0, 1) * scale,
               target.transpose(2, 0, 1), weight[None].astype(np.float32)]
        if rng.random() < 0.5:
            out = [o[:, :, ::-1] for o in out]
        if rng.random() < 0.5:
            out = [o[:, ::-1, :] for o in out]
        return [np.ascontiguousarray(o) for o in out]


def light_of(y, x):
    """The network's light estimate (over the frame's scale): its own (channels 0-2, log(1 + L))
    blended with the noisy input's by the weight sigmoid(channel 3); features.radiance_from."""
    top = float(np.log1p(F.MAX_RATIO))
    own = torch.expm1(torch.clamp(y[:, 0:3], 0.0, top))
    noisy = torch.expm1(x[:, 0:3])
    alpha = torch.sigmoid(y[:, 3:4])
    return alpha * own + (1.0 - alpha) * noisy


def loss_of(net, batch):
    x, modulation, target, weight = batch
    pred = light_of(net(x), x) * modulation
    error = (display(pred) - display(target)) ** 2
    return torch.sum(weight * error) / torch.clamp(weight.sum(), min=1.0)


def evaluate(net, frames, levels):
    """Relative RMSE of the displayed values on the parts' pixels (as the benchmark), per level:
    the noisy frame and the network's, against the target."""
    rows = []
    net.eval()
    with torch.no_grad():
        for frame in frames.frames:
            parts = frame["instance"] > 0
            if parts.sum() < 100:
                continue
            ref = display(torch.from_numpy(frame["target"].astype(np.float32))).numpy()[parts]
            for s in levels:
                if s not in frame["levels"]:
                    continue
                x, scale, r = frame["levels"][s]
                h, w = frame["depth"].shape
                hp, wp = (h + 7) // 8 * 8, (w + 7) // 8 * 8
                xp = np.zeros((1, F.CHANNELS, hp, wp), np.float32)
                xp[0, :, :h, :w] = x
                y = net(torch.from_numpy(xp))[0, :, :h, :w].numpy()
                y = F.light_channels(y, x.astype(np.float32))
                a = np.where((frame["depth"] > 0)[..., None],
                             np.maximum(F.ALBEDO_FLOOR, frame["albedo"].astype(np.float32)), 1.0)
                den = F.radiance_from(y, scale, a, r.astype(np.float32), frame["depth"])
                errs = []
                for img in (r.astype(np.float32), den):
                    d = display(torch.from_numpy(img.astype(np.float32))).numpy()[parts]
                    errs.append(float(np.sqrt(np.mean((d - ref) ** 2)) / max(ref.mean(), 1e-9)))
                rows.append((frame["name"], s, errs[0], errs[1]))
    net.train()
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", required=True)
    parser.add_argument("--minutes", type=float, default=25.0)
    parser.add_argument("--batch", type=int, default=8)
    parser.add_argument("--crop", type=int, default=128)
    parser.add_argument("--lr", type=float, default=2e-3)
    parser.add_argument("--levels", default="1,2,4,8", help="noisy sample counts to train on")
    parser.add_argument("--holdout", default="randomized_s4_",
                        help="frames whose name starts with this are kept for validation")
    parser.add_argument("--threads", type=int, default=os.cpu_count())
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--widths", default="24,48,64",
                        help="channels at 1/2, 1/4 and 1/8 of the image")
    parser.add_argument("--head", type=int, default=16, help="channels at full resolution")
    parser.add_argument("--skips", choices=["concat", "add"], default="concat",
                        help="how a decoder level reads the encoder's features at its scale: "
                        "concatenated (the shipped model) or added (fewer weights, faster)")
    parser.add_argument("--out", default=os.path.join(ROOT, "render", "models", "denoiser.onnx"))
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    torch.manual_seed(args.seed)
    rng = random.Random(args.seed)
    levels = [int(s) for s in args.levels.split(",")]

    paths = sorted(glob.glob(os.path.join(args.data, "*.npz")))
    train_paths = [p for p in paths if not os.path.basename(p).startswith(args.holdout)]
    held_paths = [p for p in paths if os.path.basename(p).startswith(args.holdout)]
    if not train_paths:
        sys.exit(f"{args.data}: no training frames (*.npz from make_data.py)")
    start = time.time()
    train, held = Frames(train_paths), Frames(held_paths)
    print(f"{len(train.frames)} training frames, {len(held.frames)} held out, "
          f"read in {time.time() - start:.0f} s", flush=True)

    widths = tuple(int(w) for w in args.widths.split(","))
    if len(widths) != 3 or min(widths) < 1 or args.head < 1:
        sys.exit(f"--widths {args.widths} --head {args.head}: three widths and a head, each >= 1")
    net = Net(widths, args.head, args.skips)
    optimiser = torch.optim.Adam(net.parameters(), lr=args.lr)
    budget = args.minutes * 60.0
    start = time.time()
    step, running = 0, None
    while True:
        elapsed = time.time() - start
        if elapsed > budget:
            break
        # Cosine decay of the learning rate over the time budget.
        for group in optimiser.param_groups:
            group["lr"] = args.lr * 0.5 * (1.0 + np.cos(np.pi * min(1.0, elapsed / budget)))
        crops = [train.crop(rng, args.crop, levels) for _ in range(args.batch)]
        batch = [torch.from_numpy(np.stack([c[i] for c in crops])) for i in range(4)]
        loss = loss_of(net, batch)
        optimiser.zero_grad()
        loss.backward()
        optimiser.step()
        running = loss.item() if running is None else 0.98 * running + 0.02 * loss.item()
        step += 1
        if step % 200 == 0:
            print(f"step {step} {elapsed / 60:.1f} min loss {running:.3e}", flush=True)

    rows = evaluate(net, held, levels)
    summary = {}
    for s in levels:
        r = [row for row in rows if row[1] == s]
        if r:
            summary[s] = (float(np.mean([x[2] for x in r])), float(np.mean([x[3] for x in r])))
            print(f"held out, {s} samples: parts error {summary[s][0]:.4f} noisy, "
                  f"{summary[s][1]:.4f} denoised ({len(r)} frames)")
    net.eval()
    dummy = torch.zeros(1, F.CHANNELS, 480, 640)
    torch.onnx.export(net, dummy, args.out, opset_version=11, input_names=["features"],
                      output_names=["light"],
                      dynamic_axes={"features": {2: "height", 3: "width"},
                                    "light": {2: "height", 3: "width"}})
    meta = {
        "made_by": "tools/denoiser/train.py " + " ".join(sys.argv[1:]),
        "date": datetime.date.today().isoformat(),
        "training_frames": [f["name"] for f in train.frames],
        "held_out_frames": [f["name"] for f in held.frames],
        "steps": step, "batch": args.batch, "crop": args.crop, "levels": levels,
        "widths": list(widths), "head": args.head, "skips": args.skips,
        "final_loss": running,
        "held_out_parts_error": {str(s): {"noisy": v[0], "denoised": v[1]}
                                 for s, v in summary.items()},
        "parameters": int(sum(p.numel() for p in net.parameters())),
    }
    with open(os.path.splitext(args.out)[0] + ".json", "w") as f:
        json.dump(meta, f, indent=1)
        f.write("\n")
    print(f"wrote {args.out} ({step} steps)")


if __name__ == "__main__":
    main()
