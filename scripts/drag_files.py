#!/usr/bin/env python3
"""Drags files over the app's window as a file manager does (the X drag-and-drop protocol,
XDND 5), holds them there, then drops them or takes them away: what xdotool cannot script.
For looking at the drop hint and the drop under Xvfb.

    DISPLAY=:77 hooke --scene cloth32 &
    DISPLAY=:77 scripts/drag_files.py --hold 3 assets/scenes/rope.ron       # dropped
    DISPLAY=:77 scripts/drag_files.py --hold 3 --leave picture.png          # taken away

Needs python-xlib (`pip install python-xlib`). The window is the first whose name starts with
"hooke" (xdotool's search), or --window. Prints the target's replies (XdndStatus: whether it
would take the drop; XdndFinished: done). Exits 1 when no window takes drops.
"""

import argparse
import os
import subprocess
import sys
import time
from urllib.parse import quote

from Xlib import X, display, protocol


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="+")
    ap.add_argument("--window", type=lambda s: int(s, 0), help="X window id (default: hooke's)")
    ap.add_argument("--at", type=int, nargs=2, default=(800, 400), metavar=("X", "Y"),
                    help="where over the screen the files are held (default: 800 400)")
    ap.add_argument("--hold", type=float, default=1.0, help="seconds held before the end")
    ap.add_argument("--leave", action="store_true", help="take the files away, do not drop")
    args = ap.parse_args()

    d = display.Display()
    atom = d.intern_atom
    window = args.window or int(subprocess.run(
        ["xdotool", "search", "--name", "^hooke"], capture_output=True, text=True,
        check=True).stdout.split()[0])
    target = d.create_resource_object("window", window)
    if not target.get_full_property(atom("XdndAware"), X.AnyPropertyType):
        print(f"window {window:#x} takes no drops (no XdndAware)", file=sys.stderr)
        return 1

    source = d.screen().root.create_window(0, 0, 1, 1, 0, X.CopyFromParent)
    source.set_selection_owner(atom("XdndSelection"), X.CurrentTime)
    uri_list = atom("text/uri-list")
    payload = "".join("file://" + quote(os.path.abspath(f)) + "\r\n" for f in args.files)

    def send(name, *data):
        data = list(data) + [0] * (5 - len(data))
        target.send_event(protocol.event.ClientMessage(
            window=target, client_type=atom(name), data=(32, data)), event_mask=0)
        d.flush()

    def answer(seconds):
        """Serves the target's requests for the file list, and prints its replies."""
        end = time.time() + seconds
        while time.time() < end:
            while d.pending_events():
                ev = d.next_event()
                if ev.type == X.SelectionRequest:
                    prop = ev.property or ev.target
                    if ev.target == uri_list:
                        ev.requestor.change_property(prop, uri_list, 8, payload.encode())
                    else:
                        prop = X.NONE
                    ev.requestor.send_event(protocol.event.SelectionNotify(
                        time=ev.time, requestor=ev.requestor, selection=ev.selection,
                        target=ev.target, property=prop), event_mask=0)
                    d.flush()
                elif ev.type == X.ClientMessage:
                    name = d.get_atom_name(ev.client_type)
                    if name != "XdndStatus" or not answer.said_status:
                        print(name, "accepted" if ev.data[1][1] & 1 else "refused")
                    answer.said_status |= name == "XdndStatus"
            time.sleep(0.01)
    answer.said_status = False

    send("XdndEnter", source.id, 5 << 24, uri_list)
    x, y = args.at
    for _ in range(max(1, round(args.hold / 0.2))):
        send("XdndPosition", source.id, 0, (x << 16) | y, X.CurrentTime, atom("XdndActionCopy"))
        answer(0.2)
    if args.leave:
        send("XdndLeave", source.id)
    else:
        send("XdndDrop", source.id, 0, X.CurrentTime)
    answer(1.0)
    return 0


if __name__ == "__main__":
    sys.exit(main())
