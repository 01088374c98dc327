#!/usr/bin/env python3
"""Random input against the app under Xvfb: clicks, drags with modifiers, the wheel, every
key, and (with python-xlib) files dragged over the window and dropped or taken away: shipped
scenes, a broken one, a picture; for a while; then whether it is still alive, what it printed
at WARN or ERROR, and its memory at the start and the end.

    cargo build --release
    scripts/hammer.py --scene pile --seconds 180             # target/release/hooke
    scripts/hammer.py --hooke "$CARGO_TARGET_DIR/release/hooke" --scene balloon

Needs xvfb-run and xdotool (Debian: xvfb, xdotool). The app's own environment lines (Xvfb's
XSETTINGS, the software renderer, XDG_RUNTIME_DIR) are listed apart from the rest. Exits 1
when the app died or printed a WARN or ERROR line of its own, 2 when it could not start.
"""

import argparse
import glob
import importlib.util
import os
import random
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)

# Lines that the environment (Xvfb, the software renderer), not hooke, causes.
ENVIRONMENT = ("XSETTINGS", "software rendering", "TEXTURE_BINDING_ARRAY", "XDG_RUNTIME_DIR",
               "XRandR", "certifiably insane")
KEYS = [*"abcdefghijklmnopqrstuvwxyz0123456789", "space", "Return", "Escape", "BackSpace",
        "Delete", "Tab", "Left", "Right", "Up", "Down", "plus", "minus", "F1", "F5"]
MODIFIERS = [[], ["shift"], ["ctrl"], ["alt"], ["shift", "ctrl"]]


def rss_kb(pid):
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1])
    except OSError:
        return None
    return None


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--hooke", default=os.path.join(ROOT, "target", "release", "hooke"))
    p.add_argument("--scene", default="pile")
    p.add_argument("--seconds", type=float, default=120.0)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--gpu", action="store_true", help="start the app with its GPU switch on")
    a = p.parse_args()
    if not os.access(a.hooke, os.X_OK):
        print(f"hammer: no hooke binary at {a.hooke}", file=sys.stderr)
        return 2
    # A display no other server holds (a killed Xvfb leaves its lock for a moment).
    n = next(n for n in range(77, 200) if not os.path.exists(f"/tmp/.X{n}-lock"))
    display = f":{n}"
    xvfb = subprocess.Popen(["Xvfb", display, "-screen", "0", "1280x800x24"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    for _ in range(50):
        if os.path.exists(f"/tmp/.X11-unix/X{n}"):
            break
        time.sleep(0.1)
    env = dict(os.environ, DISPLAY=display)
    log = open("/tmp/hammer-app.log", "w")
    app = subprocess.Popen([a.hooke, "--scene", a.scene, "--run"] + (["--gpu"] if a.gpu else []), env=env, stdout=log,
                           stderr=subprocess.STDOUT, cwd=ROOT)
    time.sleep(6)
    if app.poll() is not None:
        print("hammer: the app did not start; see /tmp/hammer-app.log", file=sys.stderr)
        xvfb.kill()
        return 2
    x = lambda *args: subprocess.run(["xdotool", *args], env=env, capture_output=True)
    wid = x("search", "--name", "hooke").stdout.split()
    if wid:
        x("windowfocus", wid[0])
    rng = random.Random(a.seed)
    drops = []
    if importlib.util.find_spec("Xlib"):
        broken, picture = "/tmp/hammer-broken.ron", "/tmp/hammer-picture.png"
        with open(broken, "w") as f:
            f.write("(particles: [(pos: (0.5, 0.5)),")
        with open(picture, "wb") as f:
            f.write(b"\x89PNG")
        drops = sorted(glob.glob(os.path.join(ROOT, "assets/scenes/*.ron"))) + [broken, picture]
    else:
        print("hammer: no python-xlib, so no files are dropped", file=sys.stderr)
    start_rss, events, dragged, end = rss_kb(app.pid), 0, 0, time.time() + a.seconds
    while time.time() < end and app.poll() is None:
        kind = rng.random()
        px, py = rng.randint(0, 1279), rng.randint(0, 799)
        mods = rng.choice(MODIFIERS)
        for m in mods:
            x("keydown", m)
        if kind < 0.35:
            x("mousemove", str(px), str(py), "click", str(rng.choice([1, 1, 1, 3])))
        elif kind < 0.65:
            button = str(rng.choice([1, 1, 3]))
            x("mousemove", str(px), str(py), "mousedown", button)
            for _ in range(rng.randint(2, 8)):
                px = min(1279, max(0, px + rng.randint(-80, 80)))
                py = min(799, max(0, py + rng.randint(-80, 80)))
                x("mousemove", str(px), str(py))
            x("mouseup", button)
        elif kind < 0.75:
            x("mousemove", str(px), str(py), "click", str(rng.choice([4, 5])))
        elif kind < 0.77 and drops:
            files = rng.sample(drops, rng.choice([1, 1, 1, 2]))
            leave = ["--leave"] if rng.random() < 0.3 else []
            subprocess.run([sys.executable, os.path.join(HERE, "drag_files.py"), "--hold",
                            f"{rng.uniform(0.2, 1.0):.2f}", "--at", str(px), str(py), *leave,
                            *files], env=env, capture_output=True, timeout=20)
            dragged += 1
        else:
            x("key", rng.choice(KEYS))
        for m in mods:
            x("keyup", m)
        events += 1
        time.sleep(rng.uniform(0.02, 0.2))
    alive = app.poll() is None
    end_rss = rss_kb(app.pid)
    app.terminate()
    try:
        app.wait(10)
    except subprocess.TimeoutExpired:
        app.kill()
    xvfb.terminate()
    xvfb.wait()
    log.close()
    lines = open("/tmp/hammer-app.log", errors="replace").read().splitlines()
    loud = [l for l in lines if ("WARN" in l or "ERROR" in l or "panicked" in l)]
    ours = [l for l in loud if not any(e in l for e in ENVIRONMENT)]
    print(f"{events} events ({dragged} file drags) in {a.seconds:.0f} s on {a.scene}; alive: {alive}; "
          f"RSS {start_rss} -> {end_rss} kB; WARN/ERROR lines: {len(ours)} ours, "
          f"{len(loud) - len(ours)} the environment's")
    for l in ours[:20]:
        print("  " + l)
    return 0 if alive and not ours else 1


if __name__ == "__main__":
    sys.exit(main())
