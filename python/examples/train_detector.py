"""A contact detector trained on geltip's synthetic frames only, scored on a real sensor's.

    python python/examples/train_detector.py                      # the full run (about 20-25 min on 2 cores)
    python python/examples/train_detector.py --quick --out runs/q  # a smoke run (a few minutes)

The sim-to-real check: `geltip dataset` renders contacts on the calibrated `allsight`
sensor; each render's change from the empty finger (its strength and tint, and a colour
shift over its footprint, drawn per sample) is put on a real no-contact frame (the t = 0
frames of the real set, one chosen per sample from its index), through JPEG. Its
reference is that frame or, half the time, another no-contact frame of the same session
(the real LEDs' drift between two moments); drift like a real sensor's is added besides (a
sector of LEDs brightening, a sub-pixel shift and a tiny turn, gain and offset, noise). A
small CNN learns contact / no contact and the contact's pixel from (frame, reference,
difference); --members of them (default 2), each from its own seed on the same frames,
answer together. No real contact frame is used for training. The real frames are then scored
by `geltip.evaluate` (the same protocol as `geltip evaluate --real`), and the predictions
are written so that

    geltip evaluate --real ../shared/real/allsight/labels.json --sensor allsight \\
        --predictions runs/sim2real/predictions.jsonl --out runs/sim2real/eval-cli

scores them again from the file. Needs PyTorch and Pillow (`pip install torch pillow`);
uses a GPU when PyTorch sees one. Writes into --out: the rendered set (synthetic/), the
models (model.pt), training.json (losses, times), predictions.jsonl and the report (eval/).

It then scores the networks on --check-count held-out geltip frames made the same way
(`geltip dataset --background` over the same real no-contact frames, another seed, drift,
a quarter empty): its error where the truth is exact (eval-synthetic/), beside the real
frames' (eval/); the difference is the sim-to-real gap.
"""
import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import time
import zlib
from io import BytesIO
from multiprocessing import Pool
from pathlib import Path

import numpy as np

import geltip

try:
    import torch
    import torch.nn as nn
    import torch.nn.functional as F
    from PIL import Image, ImageFilter
except ImportError as e:  # pragma: no cover - depends on the environment
    sys.exit(f"error: this example needs PyTorch and Pillow ({e}); pip install torch pillow")

SCALE = 4  # the network sees the frames 4x smaller (480 -> 120 for the AllSight)
HEAT_STRIDE = 4  # one heatmap cell per 4 input pixels (16 frame pixels)
CHECK_SEED = 1_000_000  # the held-out geltip frames' seed, plus --seed: never training's


def geltip_binary(given):
    """The `geltip` command: --geltip, on PATH, or this checkout's release build."""
    if given:
        return given
    found = shutil.which("geltip")
    if found:
        return found
    here = Path(__file__).resolve().parents[2] / "target" / "release" / "geltip"
    if here.is_file():
        return str(here)
    sys.exit("error: no `geltip` command: put it on PATH, pass --geltip, or cargo build --release")


def shrink(rgb):
    """(H, W, 3) uint8 -> (3, H/SCALE, W/SCALE) float32 in 0..1, by block means."""
    h, w, _ = rgb.shape
    x = rgb[: h - h % SCALE, : w - w % SCALE].astype(np.float32)
    x = x.reshape(h // SCALE, SCALE, w // SCALE, SCALE, 3).mean(axis=(1, 3))
    return np.ascontiguousarray(x.transpose(2, 0, 1)) / 255.0


def jpeg(rgb, quality):
    """`rgb` through a JPEG encoder and back, as a camera's frames come."""
    buf = BytesIO()
    Image.fromarray(rgb).save(buf, format="JPEG", quality=int(quality))
    return np.asarray(Image.open(BytesIO(buf.getvalue())).convert("RGB"))


def sample_rng(seed, k):
    """Sample k's own random numbers: the same whatever the order or the workers."""
    return np.random.default_rng([seed, k])


def background_of(k, count, seed):
    """The background of sample k, drawn from (seed, k) alone."""
    return zlib.crc32(f"{seed}:{k}".encode()) % count


def reference_of(k, b, sessions, seed):
    """Sample k's reference: half the time its own background (drift is then drawn), half
    another no-contact frame of the same session, so the LEDs' real drift between two
    moments sits between frame and reference. From (seed, k) alone."""
    h = zlib.crc32(f"{seed}:{k}:reference".encode())
    same = [i for i, s in enumerate(sessions) if s == sessions[b] and i != b]
    if h % 2 == 0 or not same:
        return b
    return same[(h // 2) % len(same)]


def footprint_tint(mask, depth, largest, rng):
    """(H, W, 3) levels to add over a contact's footprint (`mask`: 255 where the skin is
    pressed in), softened at its edge: where the skin is pressed, real imprints shift colour
    by up to ~10 levels a channel either way (blue falls where the render's rises), so each
    channel draws a shift in +-`largest`, times the press depth up to 1 mm."""
    pressed = Image.open(mask).convert("L")
    soft = np.asarray(pressed.filter(ImageFilter.GaussianBlur(2)), np.float32) / 255
    return soft[..., None] * (rng.uniform(-largest, largest, 3) * min(1.0, depth))


# Set by the pool's initializer: each worker's copy of what composing needs.
_WORK = {}


def _init_worker(backgrounds, reference, root, seed, tint):
    _WORK.update(backgrounds=backgrounds, reference=reference, root=root, seed=seed, tint=tint)


def compose(job):
    """Sample k's training frame at the network's size: its rendered change on its real
    background (or the background alone for an empty sample), through JPEG. Returns
    (frame, background index)."""
    k, image, empty, mask, depth = job
    w = _WORK
    rng = sample_rng(w["seed"], k)
    b = background_of(k, len(w["backgrounds"]), w["seed"])
    base = w["backgrounds"][b].astype(np.float32)
    if not empty:
        render = geltip.load_image(str(Path(w["root"]) / image)).astype(np.float32)
        # The imprint's strength and tint vary (its look matches real ones only roughly).
        contrast = rng.uniform(0.7, 1.5) * (1 + rng.uniform(-0.3, 0.3, 3))
        base = base + contrast * (render - w["reference"])
        if w["tint"] > 0 and mask:
            base = base + footprint_tint(Path(w["root"]) / mask, depth, w["tint"], rng)
    base = base + rng.normal(0.0, rng.uniform(0.5, 2.5), base.shape)
    rgb = np.clip(np.rint(base), 0, 255).astype(np.uint8)
    rgb = jpeg(rgb, rng.uniform(75, 97))
    return shrink(rgb), b


def render_set(args, out):
    """The synthetic contacts, rendered once by `geltip dataset` (resumed if present)."""
    root = out / "synthetic"
    cmd = [
        geltip_binary(args.geltip), "dataset", "--sensor", args.sensor,
        "--count", str(args.count), "--seed", str(args.seed), "--out", str(root),
        "--objects", args.objects, "--masks",
    ]
    print("rendering:", " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True)
    return root


def synthetic_check(args, out, real, net, device):
    """The network on held-out geltip frames whose truth is exact: `geltip dataset
    --background` over the real no-contact frames (another seed than training's), with
    drift and a quarter empty, scored by `geltip.evaluate(dataset=...)`. Returns its report."""
    folder = out / "backgrounds"
    folder.mkdir(exist_ok=True)
    for name in real_backgrounds(real):
        if not (folder / name).exists():
            try:
                os.symlink((real / name).resolve(), folder / name)
            except OSError:  # no symlinks here (some Windows setups): a copy
                shutil.copyfile(real / name, folder / name)
    root = out / "synthetic-check"
    cmd = [
        geltip_binary(args.geltip), "dataset", "--sensor", args.sensor,
        "--count", str(args.check_count), "--seed", str(CHECK_SEED + args.seed),
        "--out", str(root), "--objects", args.objects, "--background", str(folder),
        "--drift", "0.5", "--empty-fraction", "0.25",
    ]
    print("held-out geltip frames:", " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True)
    detect, _ = detector(net, device, args.threshold)
    return geltip.evaluate(detect, dataset=root, out=out / "eval-synthetic")


def real_backgrounds(real):
    """The real set's no-contact frames taken as each press starts (its t = 0 frames). The
    sessions' first frames are left out: the drift-only pairs scored are t = 0 frames
    against them, so no pair scored is ever a training pair."""
    names = sorted(p.name for p in real.iterdir() if p.name.endswith("_0.jpg"))
    if not names:
        sys.exit(f"error: {real}: no no-contact frames (*_0.jpg)")
    return names


def build_training_set(args, out, real):
    """Frames (N, 3, h, w) float16, their reference's index among the backgrounds (their own
    background or another of its session), label (pixel or none)."""
    root = render_set(args, out)
    ds = geltip.Dataset(root)
    names = real_backgrounds(real)
    backgrounds = [geltip.load_image(str(real / n)) for n in names]
    reference = geltip.load_image(str(root / "reference.png")).astype(np.float32)
    jobs, pixels = [], []
    empties = int(round(args.count * args.empty_fraction))
    for k in range(args.count):
        labels = ds.labels[k]
        # A set with empty samples labels scenes ({"contacts": [...]}); else one contact.
        contacts = labels["contacts"] if "contacts" in labels else [labels]
        contacts = [c for c in contacts if c.get("pixel") is not None]
        if contacts:
            jobs.append((k, labels["image"], False, contacts[0].get("mask", labels.get("mask")),
                         contacts[0].get("depth_mm") or 0.0))
            pixels.append(contacts[0]["pixel"])
    # Empty samples: a background alone, indices after the rendered ones.
    for e in range(empties):
        jobs.append((args.count + e, None, True, None, 0.0))
        pixels.append(None)
    t = time.time()
    init = (backgrounds, reference, str(root), args.seed, args.tint)
    with Pool(args.workers, _init_worker, init) as pool:
        done = pool.map(compose, jobs, chunksize=32)
    print(f"composed {len(done)} training frames on {len(names)} real backgrounds "
          f"in {time.time() - t:.0f} s", flush=True)
    frames = torch.from_numpy(np.stack([d[0] for d in done]).astype(np.float16))
    sessions = [n.split("_")[0] for n in names]
    which = torch.tensor([reference_of(j[0], d[1], sessions, args.seed) for j, d in zip(jobs, done)])
    refs = torch.from_numpy(np.stack([shrink(b) for b in backgrounds]).astype(np.float16))
    has = torch.tensor([p is not None for p in pixels])
    px = torch.tensor([p if p is not None else [0.0, 0.0] for p in pixels], dtype=torch.float32)
    return frames, which, refs, has, px


def drift(x, gen):
    """What a real sensor's frame does against its reference with nothing pressed, on a
    batch (B, 3, h, w): a sector of the LEDs brightens or dims, a sub-pixel shift and a
    tiny turn, per-channel gain and offset, a smooth gradient, noise."""
    b, _, h, w = x.shape
    dev = x.device
    u = lambda *s: torch.rand(*s, generator=gen, device=dev)  # noqa: E731
    ys, xs = torch.meshgrid(
        torch.linspace(-1, 1, h, device=dev), torch.linspace(-1, 1, w, device=dev), indexing="ij"
    )
    angle = torch.atan2(ys, xs)
    # The LED sector: a channel's gain bumped around one azimuth.
    centre = u(b, 1, 1, 1) * 2 * math.pi
    width = 0.3 + u(b, 1, 1, 1) * 0.9
    d = torch.remainder(angle - centre + math.pi, 2 * math.pi) - math.pi
    bump = torch.exp(-((d / width) ** 2))
    channel = F.one_hot((u(b) * 3).long().clamp(max=2), 3).float().view(b, 3, 1, 1)
    mix = channel * 0.7 + 0.3 * u(b, 3, 1, 1)
    # Real LEDs drift by up to ~58 levels over an hour (../shared/real/README.md).
    gain = 1 + (u(b, 1, 1, 1) * 2 - 1) * 0.4 * mix * bump
    gain = gain * (1 + (u(b, 3, 1, 1) * 2 - 1) * 0.12)
    grad = (u(b, 3, 1, 1) * 2 - 1) * 0.03 * xs + (u(b, 3, 1, 1) * 2 - 1) * 0.03 * ys
    offset = (u(b, 3, 1, 1) * 2 - 1) * 0.02 + grad
    # The shift (up to 0.8 frame pixels) and the turn (up to 0.6 degrees).
    turn = (u(b) * 2 - 1) * math.radians(0.6)
    shift = (u(b, 2) * 2 - 1) * 0.8 / (w * SCALE / 2)
    c, s = torch.cos(turn), torch.sin(turn)
    theta = torch.stack(
        [torch.stack([c, -s, shift[:, 0]], 1), torch.stack([s, c, shift[:, 1]], 1)], 1
    )
    grid = F.affine_grid(theta, x.shape, align_corners=False)
    x = F.grid_sample(x, grid, mode="bilinear", padding_mode="border", align_corners=False)
    x = x * gain + offset
    x = x + torch.randn(x.shape, generator=gen, device=dev) * (u(b, 1, 1, 1) * 0.006)
    return x.clamp(0, 1)


class ContactNet(nn.Module):
    """Contact / no contact and the contact's pixel, from (frame, reference, difference):
    a small encoder, a heatmap at 1/4 of its input (soft-argmax gives the pixel) and a
    presence logit from the pooled deepest features."""

    def __init__(self):
        super().__init__()

        def block(i, o, stride):
            return nn.Sequential(
                nn.Conv2d(i, o, 3, stride, 1, bias=False), nn.BatchNorm2d(o), nn.ReLU(inplace=True)
            )

        self.stem = nn.Sequential(block(9, 24, 2), block(24, 32, 1))  # 1/2
        self.mid = nn.Sequential(block(32, 48, 2), block(48, 64, 1))  # 1/4
        self.deep = nn.Sequential(block(64, 96, 2), block(96, 96, 1), block(96, 96, 1))  # 1/8
        self.heat = nn.Sequential(block(96 + 64, 48, 1), nn.Conv2d(48, 1, 1))
        self.present = nn.Linear(2 * 96, 1)

    def forward(self, frame, reference):
        x = torch.cat([frame, reference, (frame - reference) * 4], 1)
        mid = self.mid(self.stem(x))
        deep = self.deep(mid)
        up = F.interpolate(deep, size=mid.shape[-2:], mode="bilinear", align_corners=False)
        heat = self.heat(torch.cat([up, mid], 1)).flatten(1)
        pooled = torch.cat([deep.mean((2, 3)), deep.amax((2, 3))], 1)
        return self.present(pooled).squeeze(1), heat, mid.shape[-2:]


def soft_argmax(heat, shape):
    """Each heatmap's expected frame pixel (u, v)."""
    h, w = shape
    p = heat.softmax(1).view(-1, h, w)
    stride = SCALE * HEAT_STRIDE
    us = (torch.arange(w, device=heat.device) + 0.5) * stride
    vs = (torch.arange(h, device=heat.device) + 0.5) * stride
    return torch.stack([(p.sum(1) * us).sum(1), (p.sum(2) * vs).sum(1)], 1)


def heat_target(px, shape, sigma=1.0):
    """A Gaussian around each pixel on the heatmap's grid, summing to one."""
    h, w = shape
    stride = SCALE * HEAT_STRIDE
    gu = (px[:, 0] / stride - 0.5).view(-1, 1, 1)
    gv = (px[:, 1] / stride - 0.5).view(-1, 1, 1)
    vs = torch.arange(h, device=px.device).view(1, h, 1)
    us = torch.arange(w, device=px.device).view(1, 1, w)
    t = torch.exp(-((us - gu) ** 2 + (vs - gv) ** 2) / (2 * sigma**2)).flatten(1)
    return t / t.sum(1, keepdim=True)


def member_seed(seed, m):
    """Member m's training seed (its weights' start, batch order and drift): member 0
    trains exactly as a lone network of this --seed would."""
    return seed + 7919 * m


def train(args, data, device, seed):
    frames, which, refs, has, px = data
    n = len(frames)
    gen = torch.Generator(device=device).manual_seed(seed)
    cpu_gen = torch.Generator().manual_seed(seed)
    torch.manual_seed(seed)
    net = ContactNet().to(device)
    opt = torch.optim.AdamW(net.parameters(), lr=args.lr, weight_decay=1e-4)
    steps = args.epochs * math.ceil(n / args.batch)
    sched = torch.optim.lr_scheduler.OneCycleLR(opt, args.lr, total_steps=steps, pct_start=0.15)
    refs_dev = refs.to(device)
    log, step, t0 = [], 0, time.time()
    for epoch in range(args.epochs):
        order = torch.randperm(n, generator=cpu_gen)
        net.train()
        totals = np.zeros(3)
        for at in range(0, n, args.batch):
            idx = order[at : at + args.batch]
            f = frames[idx].to(device).float()
            r = refs_dev[which[idx].to(device)].float()
            # Drift on the frame's side, and some on the reference's (both drift in life).
            f = drift(f, gen)
            r = torch.where(torch.rand(len(idx), 1, 1, 1, generator=gen, device=device) < 0.3,
                            drift(r, gen), r)
            y, p = has[idx].to(device), px[idx].to(device)
            logit, heat, shape = net(f, r)
            loss_p = F.binary_cross_entropy_with_logits(logit, y.float())
            loss_h = loss_px = torch.zeros((), device=device)
            if y.any():
                hp = heat[y]
                loss_h = -(heat_target(p[y], shape) * hp.log_softmax(1)).sum(1).mean()
                loss_px = (soft_argmax(hp, shape) - p[y]).abs().mean() / 50.0
            loss = loss_p + loss_h + loss_px
            opt.zero_grad(set_to_none=True)
            loss.backward()
            opt.step()
            sched.step()
            step += 1
            totals += [loss_p.item(), loss_h.item(), loss_px.item() * 50]
        batches = math.ceil(n / args.batch)
        row = {
            "epoch": epoch + 1,
            "presence_bce": totals[0] / batches,
            "heatmap_ce": totals[1] / batches,
            "pixel_l1_px": totals[2] / batches,
            "seconds": time.time() - t0,
        }
        log.append(row)
        print(f"seed {seed}, epoch {epoch + 1}/{args.epochs}: presence {row['presence_bce']:.3f}, "
              f"heatmap {row['heatmap_ce']:.3f}, pixel {row['pixel_l1_px']:.1f} px, "
              f"{row['seconds']:.0f} s", flush=True)
    return net, log


class Ensemble(nn.Module):
    """Networks trained alike from different seeds, answering together: the mean of their
    contact probabilities and of their pixels. Averaging takes out what each one's seed
    alone decided (its own scatter), not what they all learnt."""

    def __init__(self, nets):
        super().__init__()
        self.members = nn.ModuleList(nets)

    def forward(self, frame, reference):
        probs, pixels = [], []
        for net in self.members:
            logit, heat, shape = net(frame, reference)
            probs.append(torch.sigmoid(logit))
            pixels.append(soft_argmax(heat, shape))
        return torch.stack(probs).mean(0), torch.stack(pixels).mean(0)


def detector(net, device, threshold):
    """The trained ensemble as a `geltip.evaluate` detector, remembering each answer."""
    answers = []

    @torch.no_grad()
    def detect(image, reference, sensor):
        net.eval()
        f = torch.from_numpy(shrink(image))[None].to(device)
        r = torch.from_numpy(shrink(reference))[None].to(device)
        prob, pixel = net(f, r)
        p = float(prob[0])
        found = []
        if p >= threshold:
            u, v = pixel[0].tolist()
            found = [{"pixel": [u, v], "confidence": p}]
        answers.append({"sample": len(answers), "detections": found})
        return found

    detect.__name__ = "synthetic-cnn"
    return detect, answers


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--real", default="../shared/real/allsight", type=Path,
                    help="the real set's folder (labels.json and its frames)")
    ap.add_argument("--out", default="runs/sim2real", type=Path)
    ap.add_argument("--sensor", default="allsight", help="the sensor geltip renders")
    ap.add_argument("--objects", default="sphere:r=2,sphere:r=3,sphere:r=4,sphere:r=5,sphere:r=7",
                    help="what presses the finger (geltip dataset --objects; default: spheres, "
                    "as the real set's indenter)")
    ap.add_argument("--count", type=int, default=6000, help="rendered contact samples")
    ap.add_argument("--empty-fraction", type=float, default=0.33,
                    help="extra no-contact samples, as a share of --count")
    ap.add_argument("--epochs", type=int, default=6)
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--lr", type=float, default=3e-3)
    ap.add_argument("--tint", type=float, default=12.0,
                    help="largest colour shift (8-bit levels, either sign per channel) put "
                    "over each rendered contact's footprint (0: none)")
    ap.add_argument("--check-count", type=int, default=400,
                    help="held-out geltip frames the network is scored on besides the real ones "
                    "(0: none)")
    ap.add_argument("--members", type=int, default=2,
                    help="networks trained from different seeds on the same frames, answering "
                    "together (each adds a training's time)")
    ap.add_argument("--threshold", type=float, default=0.5,
                    help="presence above which a frame is called a contact")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--geltip", help="the geltip command (default: on PATH or target/release)")
    ap.add_argument("--quick", action="store_true",
                    help="a smoke run: 400 samples, 2 epochs, 60 held-out frames")
    args = ap.parse_args()
    if args.quick:
        args.count, args.epochs = min(args.count, 400), min(args.epochs, 2)
        args.check_count = min(args.check_count, 60)
    if args.check_count < 0:
        sys.exit(f"error: --check-count must be 0 or more, got {args.check_count}")
    if args.members < 1:
        sys.exit(f"error: --members must be 1 or more, got {args.members}")
    if not args.tint >= 0:
        sys.exit(f"error: --tint must be 0 or more, got {args.tint}")
    labels = args.real / "labels.json"
    if not labels.is_file():
        sys.exit(f"error: {labels}: not found (the real set; see --real)")
    args.out.mkdir(parents=True, exist_ok=True)
    device = "cuda" if torch.cuda.is_available() else "cpu"
    where = torch.cuda.get_device_name(0) if device == "cuda" else f"CPU, {torch.get_num_threads()} threads"
    print(f"training on {where}", flush=True)

    t = time.time()
    data = build_training_set(args, args.out, args.real)
    prepared = time.time() - t
    nets, logs = [], []
    for m in range(args.members):
        seed = member_seed(args.seed, m)
        net, log = train(args, data, device, seed)
        nets.append(net)
        logs.append({"seed": seed, "epochs": log})
    net = Ensemble(nets)
    trained = time.time() - t - prepared
    torch.save({"members": [n.state_dict() for n in nets]}, args.out / "model.pt")

    detect, answers = detector(net, device, args.threshold)
    t = time.time()
    report = geltip.evaluate(detect, real=labels, sensor=args.sensor, out=args.out / "eval")
    scored = time.time() - t
    with open(args.out / "predictions.jsonl", "w") as f:
        for a in answers:
            f.write(json.dumps(a) + "\n")
    check = synthetic_check(args, args.out, args.real, net, device) if args.check_count else None
    (args.out / "training.json").write_text(json.dumps({
        "device": where, "samples": len(data[0]), "members": logs,
        "prepare_s": prepared, "train_s": trained, "score_s": scored,
        "synthetic_check": check and {
            k: check.summary.get(k) for k in (
                "visible", "detected", "recall", "error_px", "error_mm", "empty_frames",
                "false_positives_on_empty_frames", "false_positives", "average_precision")
        },
        "args": {k: str(v) for k, v in vars(args).items()},
    }, indent=1))
    print(report.tables)
    if check:
        print("\nOn held-out geltip frames (exact truth; the sim-to-real gap is the difference):")
        print(check.tables.split("\n## ")[0])
    print(f"prepared {prepared:.0f} s, trained {trained:.0f} s on {where}, scored {scored:.0f} s; "
          f"wrote {args.out}")


if __name__ == "__main__":
    main()
