"""The explorer's instant tier in the browser: from a change of U* to the redrawn page
(N = 10), measured in the system's Chromium driven by Playwright against a fresh
``fsicas explore`` server on a free port of 127.0.0.1.

Three medians over ``--changes`` changes of U* (4 to 6), each the time from the box's
change event to:

* ``readouts``: the growth rate's readout showing the new value, changes one after the
  other (the next made as soon as the readout changed, while the page may still be
  drawing the figures of the last one: what ``test_instant_tier_latency_in_the_browser``
  prints);
* ``readouts, paced``: the same with 0.3 s between changes (a user typing values);
* ``figures, paced``: the eigenvalue figure's data replaced and the frame after it drawn
  (the figures are sent after the readouts, in a second message).

    python benchmarks/bench_explore.py [--changes 9] [--repeats 3]

Takes about 30 s a repeat. Needs /usr/bin/chromium and the ``explore`` and ``test`` extras.
"""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
from common import machine  # noqa: E402
from tests.test_explore import CHROMIUM, FIND, FLAGS, LATENCY, _free_port  # noqa: E402

#: Like LATENCY, also the time until the eigenvalue figure's data source changed and the
#: next frame was drawn (ms): [readout, figure].
FULL = """async ([id, value, out]) => { const find = %s;
  const doc = Bokeh.documents[0];
  const src = [...doc._all_models.values()].find(m => m.constructor.__name__ ===
      "ColumnDataSource" && (m.data instanceof Map ? m.data.has("re") : "re" in m.data));
  let figure = null;
  const mark = () => { requestAnimationFrame(() => { figure = performance.now(); }); };
  src.properties.data.change.connect(mark);
  const box = find(document, id), old = find(document, out).textContent;
  const t0 = performance.now(); box.value = value; box.dispatchEvent(new Event('change'));
  let shown = null;
  while (shown === null || figure === null) {
    await new Promise(r => requestAnimationFrame(r));
    if (shown === null && find(document, out).textContent !== old) shown = performance.now();
    if (performance.now() - t0 > 10000) return [-1, -1]; }
  src.properties.data.change.disconnect(mark);
  return [shown - t0, figure - t0]; }""" % FIND


def measure(url: str, changes: int) -> dict:
    """The three medians (ms) of one page load."""
    from playwright.sync_api import sync_playwright
    values = [f"{4.0 + 2.0 * i / (changes - 1):.3f}" for i in range(changes)]
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
        page = browser.new_page(viewport={"width": 1400, "height": 1000})
        page.goto(url)
        page.locator("[data-testid=command]").wait_for(timeout=60000)
        time.sleep(2.0)
        rapid = [page.evaluate(LATENCY, ["ustar", v, "growth-rate"]) for v in values]
        paced = []
        for v in values:
            v = f"{float(v) + 0.1:.3f}"              # each a change from the last
            time.sleep(0.3)
            paced.append(page.evaluate(FULL, ["ustar", v, "growth-rate"]))
        browser.close()
    if min(rapid) < 0 or min(min(t) for t in paced) < 0:
        raise RuntimeError(f"a change was not shown within 10 s: {rapid} {paced}")
    return {"readouts": statistics.median(rapid),
            "readouts, paced": statistics.median(t[0] for t in paced),
            "figures, paced": statistics.median(t[1] for t in paced)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--changes", type=int, default=9)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    port = _free_port()
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    server = subprocess.Popen([sys.executable, "-m", "fsicas.cli", "explore", "--port", str(port)],
                              env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                              text=True, stdin=subprocess.DEVNULL)
    try:
        for _ in range(2):
            server.stdout.readline()
        runs = []
        for _ in range(args.repeats):
            runs.append(measure(f"http://127.0.0.1:{port}/", args.changes))
            print(f"  load {os.getloadavg()[0]:.1f}: " + ", ".join(
                f"{k} {v:.0f} ms" for k, v in runs[-1].items()), file=sys.stderr)
    finally:
        server.terminate()
        server.wait(timeout=10)
    print(f"\n{machine()}\n")
    print("| from a change of U* (N = 10) to | median of each repeat (ms) |")
    print("| --- | --- |")
    for key in runs[0]:
        print(f"| {key} | {', '.join(f'{r[key]:.0f}' for r in runs)} |")


if __name__ == "__main__":
    main()
