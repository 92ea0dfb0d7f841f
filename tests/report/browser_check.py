#!/usr/bin/env python3
"""Opens an HTML page from disk in headless Chromium and checks it the way a reader would see it.

  browser_check.py PAGE.html --screenshot OUT.png [--sort-check] [--full-page | --element SELECTOR]

Fails (exit 1, one line per problem) when an image did not load, the console or the page reported an error, the
page asked for anything but local files, or (--sort-check) clicking a column of table.rows does not sort it.
Saves a screenshot of the top of the page (or all of it). Exit 77 when Chromium is not installed (the test is then skipped).

Chromium is driven over the DevTools protocol on a pipe (--remote-debugging-pipe: NUL-separated JSON on file
descriptors 3 and 4), so nothing but the Python standard library is needed and no port is opened.
"""
import argparse
import base64
import fcntl
import json
import os
import pathlib
import select
import shutil
import subprocess
import sys
import tempfile
import time

CHROMIUM_FLAGS = [
    "--headless=new", "--no-sandbox", "--disable-gpu", "--no-first-run", "--no-default-browser-check",
    "--disable-background-networking", "--disable-component-update", "--disable-sync", "--disable-quic",
    "--disable-extensions", "--mute-audio", "--hide-scrollbars", "--remote-debugging-pipe",
    # file:// pages may load their neighbours (images/ beside index.html)
    "--allow-file-access-from-files",
]


class Browser:
    def __init__(self, executable, profile):
        # Chromium reads the protocol from descriptor 3 and writes to 4. The pipe's ends are first moved above
        # 9 so that the redirections onto 3 and 4 cannot overwrite one another (bash: dash takes one-digit descriptors only).
        self._log = tempfile.TemporaryFile()  # Chromium's own chatter: read only when it dies
        to_browser_r, self.to_browser = self._high(os.pipe())
        self.from_browser, from_browser_w = self._high(os.pipe())
        command = f'exec "$0" "$@" 3<&{to_browser_r} 4>&{from_browser_w} {to_browser_r}<&- {from_browser_w}>&-'
        self.process = subprocess.Popen(
            ["/bin/bash", "-c", command, executable, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", "about:blank"],
            pass_fds=(to_browser_r, from_browser_w), stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
            stderr=self._log)
        os.close(to_browser_r)
        os.close(from_browser_w)
        self.buffer = b""
        self.next_id = 0
        self.events = []

    @staticmethod
    def _high(fds):
        moved = tuple(fcntl.fcntl(fd, fcntl.F_DUPFD_CLOEXEC, 10) for fd in fds)
        for fd in fds:
            os.close(fd)
        return moved

    def send(self, method, params=None, session=None, timeout=30):
        self.next_id += 1
        message = {"id": self.next_id, "method": method, "params": params or {}}
        if session:
            message["sessionId"] = session
        os.write(self.to_browser, json.dumps(message).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while True:
            reply = self.receive(deadline)
            if reply.get("id") == self.next_id:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error'].get('message')}")
                return reply.get("result", {})

    def receive(self, deadline):
        while b"\0" not in self.buffer:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self.from_browser], [], [], left)[0]:
                raise TimeoutError("Chromium did not answer in time")
            chunk = os.read(self.from_browser, 1 << 20)
            if not chunk:
                self._log.seek(0)
                raise RuntimeError("Chromium closed the pipe: " + self._log.read().decode(errors="replace")[-500:])
            self.buffer += chunk
        message, self.buffer = self.buffer.split(b"\0", 1)
        parsed = json.loads(message)
        if "method" in parsed:
            self.events.append(parsed)
        return parsed

    def wait_for(self, method, timeout=30):
        deadline = time.monotonic() + timeout
        while True:
            for event in self.events:
                if event["method"] == method:
                    return event
            self.receive(deadline)

    def close(self):
        try:
            self.send("Browser.close", timeout=5)
        except Exception:  # noqa: BLE001 (closing anyway)
            pass
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        os.close(self.to_browser)
        os.close(self.from_browser)
        self._log.close()


IMAGES = """JSON.stringify([...document.images].map(i => ({src: i.getAttribute('src'), complete: i.complete,
  width: i.naturalWidth})))"""

SORT = """(() => {
  const table = document.querySelector('table.rows');
  if (!table) return 'no table.rows';
  const header = table.tHead.rows[0].cells[0];
  const first = () => [...table.tBodies[0].rows].map(r => Number(r.cells[0].dataset.v));
  header.click(); header.click();  // ascending, then descending
  const values = first();
  for (let i = 1; i < values.length; ++i) if (values[i - 1] < values[i]) return 'not sorted descending: ' + values;
  return 'ok';
})()"""


def check(page, screenshot, sort_check, width, height, full_page, element=None):
    executable = shutil.which("chromium") or shutil.which("chromium-browser")
    if not executable:
        print("browser_check: SKIP: chromium is not installed (Debian package chromium; scripts/setup installs it)")
        return 77
    problems = []
    profile = tempfile.mkdtemp(prefix="qdmr-chromium-")
    browser = Browser(executable, profile)
    try:
        target = browser.send("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = browser.send("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        for domain in ("Page", "Runtime", "Log", "Network"):
            browser.send(f"{domain}.enable", session=session)
        browser.send("Emulation.setDeviceMetricsOverride",
                     {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False}, session=session)
        browser.events.clear()
        url = pathlib.Path(page).resolve().as_uri()
        browser.send("Page.navigate", {"url": url}, session=session)
        browser.wait_for("Page.loadEventFired", timeout=60)
        images = json.loads(browser.send("Runtime.evaluate", {"expression": IMAGES, "returnByValue": True},
                                         session=session)["result"]["value"])
        for image in images:
            if not image["complete"] or image["width"] == 0:
                problems.append(f"image did not load: {image['src']}")
        if sort_check:
            result = browser.send("Runtime.evaluate", {"expression": SORT, "returnByValue": True}, session=session)
            if result["result"].get("value") != "ok":
                problems.append(f"sorting table.rows: {result['result'].get('value')}")
        time.sleep(0.2)  # late console messages
        for event in browser.events:
            method, params = event["method"], event.get("params", {})
            if method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert", "warning"):
                text = " ".join(str(a.get("value", a.get("description", ""))) for a in params.get("args", []))
                problems.append(f"console {params['type']}: {text}")
            elif method == "Runtime.exceptionThrown":
                details = params.get("exceptionDetails", {})
                problems.append(f"exception: {details.get('exception', {}).get('description') or details.get('text')}")
            elif method == "Log.entryAdded" and params.get("entry", {}).get("level") in ("error", "warning"):
                entry = params["entry"]
                problems.append(f"log {entry['level']}: {entry.get('text')} {entry.get('url', '')}".strip())
            elif method == "Network.requestWillBeSent":
                request_url = params.get("request", {}).get("url", "")
                if not request_url.startswith(("file:", "data:", "about:")):
                    problems.append(f"the page asked the network for {request_url}")
        capture = {"format": "png"}
        if element:  # one element of the page (e.g. a section of the report), as tall as it is (capped)
            box = browser.send("Runtime.evaluate", {"returnByValue": True, "expression":
                               f"(() => {{ const r = document.querySelector({json.dumps(element)})"
                               ".getBoundingClientRect(); return [r.x, r.y + window.scrollY, r.width, r.height]; })()"},
                               session=session)["result"].get("value")
            if not box:
                raise RuntimeError(f"no element {element} on the page")
            capture.update(captureBeyondViewport=True, clip={"x": box[0], "y": box[1], "width": box[2], "scale": 1,
                                                                "height": min(box[3], 3000)})
        elif full_page:  # the whole page, as tall as its content (capped: a screenshot, not an archive)
            size = browser.send("Page.getLayoutMetrics", session=session)["cssContentSize"]
            capture.update(captureBeyondViewport=True, clip={"x": 0, "y": 0, "width": width, "scale": 1,
                                                                "height": min(size["height"], 20000)})
        shot = browser.send("Page.captureScreenshot", capture, session=session)
        pathlib.Path(screenshot).write_bytes(base64.b64decode(shot["data"]))
        print(f"browser_check: {page}: {len(images)} images, {len(problems)} problem(s); screenshot {screenshot}")
    finally:
        browser.close()
        shutil.rmtree(profile, ignore_errors=True)
    for p in problems:
        print(f"browser_check: {page}: {p}", file=sys.stderr)
    return 1 if problems else 0


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("page")
    parser.add_argument("--screenshot", required=True)
    parser.add_argument("--sort-check", action="store_true")
    parser.add_argument("--width", type=int, default=1280)
    parser.add_argument("--height", type=int, default=1000)
    parser.add_argument("--full-page", action="store_true", help="screenshot the whole page, not the first screen")
    parser.add_argument("--element", help="screenshot only the element this CSS selector finds (e.g. #pareto)")
    args = parser.parse_args()
    if not os.path.isfile(args.page):
        print(f"browser_check: {args.page}: no such file", file=sys.stderr)
        return 2
    return check(args.page, args.screenshot, args.sort_check, args.width, args.height, args.full_page,
                 args.element)


if __name__ == "__main__":
    sys.exit(main())
