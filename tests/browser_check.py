#!/usr/bin/env python3
"""browser_check.py: opens a `cbvh report --html` page in headless Chromium over the DevTools protocol
(a pipe, no extra packages), checks console and page errors, every plot element, label boxes as the browser
lays them out, hover/focus details, and saves a full-page screenshot.

usage: browser_check.py CHROMIUM PAGE.html SCREENSHOT.png MESHES ROWS_PER_MESH
Exit 0 when every check passes, 1 with the failures on stderr."""
import base64, json, os, subprocess, sys, tempfile, time

chromium, page, shot, meshes, rows = sys.argv[1], os.path.abspath(sys.argv[2]), sys.argv[3], int(sys.argv[4]), int(sys.argv[5])

# The checks, run in the page: what a reader needs is there and legible.
MEASURE = r"""(() => {
  const out = { sections: [], errors: [] };
  const inside = (b, w, h) => b.x >= -0.5 && b.y >= -0.5 && b.x + b.width <= w + 0.5 && b.y + b.height <= h + 0.5;
  const overlap = (a, b) => a.x < b.x + b.width - 0.5 && b.x < a.x + a.width - 0.5 &&
                            a.y < b.y + b.height - 0.5 && b.y < a.y + a.height - 0.5;
  for (const sec of document.querySelectorAll("section.mesh")) {
    const s = { plots: [], advice: (sec.querySelector("p.advice") || {}).textContent || "",
                rows: sec.querySelectorAll("table.summary tbody tr").length,
                legend: sec.querySelectorAll("figure.legend svg text").length };
    for (const svg of sec.querySelectorAll(".plots svg.plot")) {
      const vb = svg.viewBox.baseVal, name = svg.getAttribute("aria-label");
      // an element's box as laid out (rotation included), in the picture's own units
      const box = el => { const r = el.getBoundingClientRect(), R = svg.getBoundingClientRect(), sx = vb.width / R.width, sy = vb.height / R.height;
                          return { x: (r.x - R.x) * sx, y: (r.y - R.y) * sy, width: r.width * sx, height: r.height * sy }; };
      const p = { name, points: svg.querySelectorAll("g.pt").length, marks: svg.querySelectorAll("path.mark").length,
                  labels: svg.querySelectorAll("text.label").length, front: svg.querySelectorAll("path.front").length,
                  tips: svg.querySelectorAll("g.tip").length, ticks: 0 };
      const labels = [...svg.querySelectorAll("text.label")].map(box);
      const marks = [...svg.querySelectorAll("path.mark")].map(box);
      for (const t of svg.querySelectorAll("text")) {
        if (t.closest("g.tip")) continue;
        const b = box(t);
        if (!inside(b, vb.width, vb.height)) out.errors.push(name + ": text '" + t.textContent + "' leaves the canvas");
      }
      labels.forEach((a, i) => {
        labels.forEach((b, j) => { if (j > i && overlap(a, b)) out.errors.push(name + ": labels " + i + " and " + j + " overlap"); });
        marks.forEach((m, j) => { if (overlap(a, m)) out.errors.push(name + ": label " + i + " covers marker " + j); });
      });
      // hover/focus: focusing a point shows its detail box, which names the configuration
      const pt = svg.querySelector("g.pt"), tip = pt && pt.nextElementSibling;
      if (!pt || !tip || getComputedStyle(tip).visibility !== "hidden") out.errors.push(name + ": detail box missing or shown before focus");
      else {
        pt.focus();
        const shown = getComputedStyle(tip).visibility === "visible", text = tip.textContent, tb = box(tip);
        pt.blur();
        if (!shown) out.errors.push(name + ": focus does not show the detail box");
        if (!/layout/.test(text) || !/ns per ray|open/.test(text)) out.errors.push(name + ": detail box lacks configuration or figures: " + text);
        if (!inside(tb, vb.width, vb.height)) out.errors.push(name + ": detail box leaves the canvas: " + JSON.stringify(tb));
      }
      s.plots.push(p);
    }
    out.sections.push(s);
  }
  return JSON.stringify(out);
})()"""


class Browser:
    def __init__(self):
        self.prof = tempfile.mkdtemp(prefix="cbvh-chromium-")
        to_chrome_r, self.to_chrome = os.pipe()
        self.from_chrome, from_chrome_w = os.pipe()
        # --remote-debugging-pipe: the browser reads commands on fd 3 and writes replies on fd 4
        self.proc = subprocess.Popen(
            ["sh", "-c", 'exec "$@" 3<&%d 4>&%d' % (to_chrome_r, from_chrome_w), "sh", chromium, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--remote-debugging-pipe",
             "--user-data-dir=" + self.prof, "--hide-scrollbars", "about:blank"],
            pass_fds=(to_chrome_r, from_chrome_w), stdout=subprocess.DEVNULL, stderr=open(os.environ.get("CBVH_CHROMIUM_LOG", os.devnull), "w"))
        os.close(to_chrome_r)
        os.close(from_chrome_w)
        self.next_id, self.buf, self.events = 0, b"", []

    def _read(self):
        while b"\0" not in self.buf:
            chunk = os.read(self.from_chrome, 1 << 16)
            if not chunk:
                raise RuntimeError("Chromium closed the DevTools pipe")
            self.buf += chunk
        msg, self.buf = self.buf.split(b"\0", 1)
        return json.loads(msg)

    def call(self, method, session=None, **params):
        self.next_id += 1
        msg = {"id": self.next_id, "method": method, "params": params}
        if session:
            msg["sessionId"] = session
        os.write(self.to_chrome, json.dumps(msg).encode() + b"\0")
        while True:
            m = self._read()
            if m.get("id") == self.next_id:
                if "error" in m:
                    raise RuntimeError(method + ": " + json.dumps(m["error"]))
                return m.get("result", {})
            self.events.append(m)

    def wait_event(self, name, timeout=60):
        end = time.time() + timeout
        while time.time() < end:
            for i, e in enumerate(self.events):
                if e.get("method") == name:
                    return self.events.pop(i)
            self.events.append(self._read())
        raise RuntimeError("no " + name + " within %d s" % timeout)

    def close(self):
        try:
            self.call("Browser.close")
        except Exception:
            pass
        try:
            self.proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        subprocess.run(["rm", "-rf", self.prof])


def main():
    failures = []
    b = Browser()
    try:
        target = b.call("Target.createTarget", url="about:blank")["targetId"]
        s = b.call("Target.attachToTarget", targetId=target, flatten=True)["sessionId"]
        for domain in ("Page", "Runtime", "Log"):
            b.call(domain + ".enable", s)
        b.call("Emulation.setDeviceMetricsOverride", s, width=1560, height=1200, deviceScaleFactor=1, mobile=False)
        b.call("Page.navigate", s, url="file://" + page)
        b.wait_event("Page.loadEventFired")
        result = json.loads(b.call("Runtime.evaluate", s, expression=MEASURE, returnByValue=True)["result"]["value"])
        metrics = b.call("Page.getLayoutMetrics", s)["cssContentSize"]
        png = b.call("Page.captureScreenshot", s, format="png", captureBeyondViewport=True,
                     clip={"x": 0, "y": 0, "width": metrics["width"], "height": metrics["height"], "scale": 1})
        with open(shot, "wb") as f:
            f.write(base64.b64decode(png["data"]))
        # Anything the console or the log reported is an error: the page has no script and fetches nothing.
        for e in b.events:
            m, p = e.get("method"), e.get("params", {})
            if m == "Runtime.consoleAPICalled":
                failures.append("console %s: %s" % (p.get("type"), " ".join(str(a.get("value")) for a in p.get("args", []))))
            elif m == "Runtime.exceptionThrown":
                failures.append("exception: " + json.dumps(p.get("exceptionDetails", {}))[:300])
            elif m == "Log.entryAdded" and p.get("entry", {}).get("level") in ("error", "warning"):
                failures.append("log %s: %s" % (p["entry"]["level"], p["entry"].get("text")))
    finally:
        b.close()

    failures += result["errors"]
    if len(result["sections"]) != meshes:
        failures.append("%d mesh sections, expected %d" % (len(result["sections"]), meshes))
    for k, sec in enumerate(result["sections"]):
        if sec["rows"] != rows or "Recommended: " not in sec["advice"] or sec["legend"] < 3:
            failures.append("section %d: %d table rows (expected %d), advice %r, %d legend texts"
                            % (k, sec["rows"], rows, sec["advice"][:60], sec["legend"]))
        if len(sec["plots"]) != 6:
            failures.append("section %d: %d plots, expected 6" % (k, len(sec["plots"])))
        for p in sec["plots"]:
            # every configuration is a point, except that the float-box reference has no open time
            want = rows - 1 if p["name"].startswith("Compression") else rows
            if not (p["points"] == p["marks"] == p["tips"] == p["labels"] == want and p["front"] == 1):
                failures.append("section %d, %s: %s (expected %d points, labels and detail boxes, one front)"
                                % (k, p["name"], json.dumps(p), want))
    if not os.path.getsize(shot) > 10000:
        failures.append("the screenshot is (nearly) empty")
    for f in failures:
        print("browser_check: " + f, file=sys.stderr)
    print("browser_check: %d sections, %d plots, %d failures; screenshot %s (%d bytes)"
          % (len(result["sections"]), sum(len(s["plots"]) for s in result["sections"]), len(failures), shot,
             os.path.getsize(shot)))
    return 1 if failures else 0


sys.exit(main())
