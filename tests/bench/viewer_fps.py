#!/usr/bin/env python3
"""viewer_fps.py — the viewer's figures in headless Chromium (software GL):
opens URL (a job page with ?bench=MS) in a real-time browser driven over
the DevTools protocol on a pipe (no virtual time: the frame rates are
wall-clock), waits until the page has measured, and prints the body's
data-* figures as "name: value" lines.

Usage: viewer_fps.py CHROMIUM URL [TIMEOUT_S]
"""
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time


def main():
    chrome, url = sys.argv[1], sys.argv[2]
    timeout = float(sys.argv[3]) if len(sys.argv) > 3 else 120
    to_r, to_w = os.pipe()      # browser reads commands on fd 3
    from_r, from_w = os.pipe()  # and writes replies on fd 4
    profile = tempfile.mkdtemp(prefix="viewer-fps.")

    def fds():
        os.dup2(to_r, 3)
        os.dup2(from_w, 4)

    proc = subprocess.Popen(
        [chrome, "--headless", "--no-sandbox", "--no-first-run",
         "--user-data-dir=" + profile, "--disable-extensions", "--mute-audio",
         "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
         "--window-size=1200,800", "--remote-debugging-pipe", "about:blank"],
        preexec_fn=fds, pass_fds=(3, 4), stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL, start_new_session=True)
    os.close(to_r)
    os.close(from_w)
    out, inp = os.fdopen(to_w, "wb"), os.fdopen(from_r, "rb")
    buf = b""
    ident = 0

    def call(method, params=None, session=None):
        nonlocal buf, ident
        ident += 1
        msg = {"id": ident, "method": method, "params": params or {}}
        if session:
            msg["sessionId"] = session
        out.write(json.dumps(msg).encode() + b"\0")
        out.flush()
        while True:
            while b"\0" not in buf:
                chunk = os.read(inp.fileno(), 1 << 16)
                if not chunk:
                    raise SystemExit("viewer_fps: the browser went away")
                buf += chunk
            raw, buf = buf.split(b"\0", 1)
            reply = json.loads(raw)
            if reply.get("id") == ident:
                if "error" in reply:
                    raise SystemExit("viewer_fps: %s: %s" % (method, reply["error"]))
                return reply["result"]

    try:
        target = call("Target.createTarget", {"url": url})["targetId"]
        session = call("Target.attachToTarget",
                       {"targetId": target, "flatten": True})["sessionId"]
        t0 = time.time()
        data = {}
        while time.time() - t0 < timeout:
            r = call("Runtime.evaluate", {
                "expression": "JSON.stringify(document.body ? document.body.dataset : {})",
                "returnByValue": True}, session)
            data = json.loads(r["result"].get("value") or "{}")
            if data.get("fpsFull") or data.get("errors") not in (None, "0"):
                break
            time.sleep(0.5)
        for k in sorted(data):
            print("%s: %s" % (k, data[k]))
        if not data.get("fpsFull"):
            raise SystemExit("viewer_fps: no figures within %g s" % timeout)
    finally:
        # the browser and its renderer and GPU processes
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        proc.wait()
        shutil.rmtree(profile, ignore_errors=True)


if __name__ == "__main__":
    main()
