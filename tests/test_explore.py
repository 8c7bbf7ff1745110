"""fsicas explore in a real browser (the system's Chromium driven by Playwright): the page
shows what the library computes, refuses bad input with the library's message, keeps its
state in the URL, moves the point where the map is clicked, and requests nothing from
outside 127.0.0.1. Skipped (with the reason) where /usr/bin/chromium is absent; CI
installs it (.ci/run)."""
import json
import os
import socket
import statistics
import subprocess
import sys
import time
from pathlib import Path
from urllib.parse import urlparse

import numpy as np
import pytest
import scipy.linalg

from fsicas import Scene
from fsicas.cycles.collocation import cycle_branch
from fsicas.linear import critical_velocity, linear_stability
from fsicas.model.assembly import build_model
from fsicas.physical import Physical, load_physical, parse_flow
from fsicas.scene import load_scene
from fsicas.timedomain.run import run_case

ROOT = Path(__file__).resolve().parents[1]
CHROMIUM = "/usr/bin/chromium"
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync"]

pytestmark = pytest.mark.skipif(not os.path.exists(CHROMIUM),
                                reason=f"no system Chromium at {CHROMIUM} (apt-get install chromium)")
sync_api = pytest.importorskip("playwright.sync_api", reason="needs playwright (the test extra)")
pytest.importorskip("panel", reason="needs panel (the explore extra)")

#: The text of the element with data-testid ``id`` (searched through shadow roots).
FIND = """(root, id) => { const find = (r) => { const e = r.querySelector(`[data-testid="${id}"]`);
  if (e) return e; for (const h of r.querySelectorAll('*')) { if (h.shadowRoot) {
  const f = find(h.shadowRoot); if (f) return f; } } return null; }; return find(root); }"""
#: Set the input ``id`` to ``value`` and time until the readout ``out`` changes (ms).
LATENCY = """async ([id, value, out]) => { const find = %s;
  const box = find(document, id), shown = find(document, out), old = shown.textContent;
  const t0 = performance.now(); box.value = value; box.dispatchEvent(new Event('change'));
  while (find(document, out).textContent === old) {
    await new Promise(r => requestAnimationFrame(r));
    if (performance.now() - t0 > 10000) return -1; }
  return performance.now() - t0; }""" % FIND


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def server():
    """``fsicas explore`` on a free port of 127.0.0.1 (this tree's code); its URL."""
    port = _free_port()
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen([sys.executable, "-m", "fsicas.cli", "explore", "--port", str(port)],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            stdin=subprocess.DEVNULL)
    lines = [proc.stdout.readline() for _ in range(2)]
    assert "serving" in lines[-1], "".join(lines) + proc.stdout.read()
    yield f"http://127.0.0.1:{port}/"
    proc.terminate()
    proc.wait(timeout=10)


@pytest.fixture(scope="module")
def browser():
    with sync_api.sync_playwright() as p:
        chromium = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
        yield chromium
        chromium.close()


@pytest.fixture
def page(browser, server):
    """A page with every request it makes recorded in ``page.requests``."""
    page = browser.new_page(viewport={"width": 1400, "height": 1000})
    page.requests = []
    page.on("request", lambda r: page.requests.append(r.url))
    yield page
    outside = [u for u in page.requests if not u.startswith("data:")
               and urlparse(u.removeprefix("blob:")).hostname != "127.0.0.1"]
    page.close()
    assert not outside, f"requests left 127.0.0.1: {outside}"


def _open(page, url: str, **values):
    """Load ``url`` (``values``: its query, e.g. ustar=6) and wait until the page shows
    the scene of that query (the command line reads ``--ustar 6``)."""
    query = "&".join(f"{k}={v:g}" for k, v in values.items())
    page.goto(url + ("?" + query if query else ""))
    page.locator("[data-testid=command]").wait_for(timeout=30000)
    for k, v in values.items():
        page.wait_for_function(f"s => ({FIND})(document, 'command').textContent.includes(s)",
                               arg=f"--{k} {v:g} ")


def _text(page, testid: str) -> str:
    return page.locator(f"[data-testid={testid}]").inner_text()


def _set(page, testid: str, value: str) -> None:
    """Type ``value`` into the input ``testid`` and wait until the page has answered (its
    command line or its error changed)."""
    state = f"() => ['command', 'error'].map(i => ({FIND})(document, i).textContent).join('|')"
    old = page.evaluate(state)
    box = page.locator(f"[data-testid={testid}]")
    box.fill(value)
    box.press("Enter")
    page.wait_for_function(f"old => ({state})() !== old", arg=old)


def _export(page) -> dict:
    """The JSON that "export the view (JSON)" downloads."""
    with page.expect_download() as download:
        page.get_by_role("button", name="export the view (JSON)").click()
    return json.loads(Path(download.value.path()).read_text())


def _number(page, testid: str) -> float:
    return float(_text(page, testid))


def test_the_page_shows_the_library_eigen_analysis_and_an_independent_eig(page, server, tmp_path):
    _open(page, server, ustar=6)
    scene = Scene(ustar=6.0)
    stab = linear_stability(scene)
    assert _text(page, "stability") == ("stable" if stab.stable else "unstable") == "unstable"
    model = build_model(scene)
    J = np.array(model.jac_rhs(stab.steady.x, stab.steady.p))
    M = np.array(model.mass(stab.steady.x, stab.steady.p))
    lam = scipy.linalg.eig(np.linalg.solve(M, J), right=False)     # standard, not QZ
    top = lam[np.argmax(lam.real)]
    assert _number(page, "growth-rate") == pytest.approx(top.real, rel=1e-5)
    assert _number(page, "frequency") == pytest.approx(abs(top.imag), rel=1e-5)
    assert "fsicas eig --mstar 1 --ustar 6 " in _text(page, "command")
    # the docs' screenshot is rewritten only when asked (FSICAS_DOC_SCREENSHOTS=1)
    shot = ROOT / "docs" / "figures" / "explore.png" if os.environ.get(
        "FSICAS_DOC_SCREENSHOTS") else tmp_path / "explore.png"
    page.screenshot(path=str(shot), full_page=True)
    assert shot.stat().st_size > 10_000


def _choose(page, testid: str, option: str) -> None:
    """Choose ``option`` in the menu ``testid`` and wait until the page has answered."""
    state = f"() => ['command', 'error'].map(i => ({FIND})(document, i).textContent).join('|')"
    old = page.evaluate(state)
    page.locator(f"[data-testid={testid}]").select_option(option)
    page.wait_for_function(f"old => ({state})() !== old", arg=old)


def _top_eigenvalue(scene: Scene) -> complex:
    """The least stable eigenvalue of ``scene`` by ``scipy.linalg.eig`` of M^-1 dF/dx at
    the library's steady state (not the library's eigen-solver)."""
    model = build_model(scene)
    steady = linear_stability(scene).steady
    J = np.array(model.jac_rhs(steady.x, steady.p))
    M = np.array(model.mass(steady.x, steady.p))
    lam = scipy.linalg.eig(np.linalg.solve(M, J), right=False)
    return lam[np.argmax(lam.real)]


def test_the_beam_ends_and_the_flow_direction_are_inputs(page, server):
    """Every beam end and both directions: the readouts are the eigenvalues of
    M^-1 dF/dx (scipy), the onset the library's; the address and the command carry them."""
    _open(page, server, ustar=3, modes=4)
    _choose(page, "direction", "reverse")
    scene = Scene(ustar=-3.0, modes=4)
    top = _top_eigenvalue(scene)
    assert _number(page, "growth-rate") == pytest.approx(top.real, rel=1e-5)
    assert "--ustar -3 " in _text(page, "command")
    page.wait_for_function("() => location.search.includes('direction=reverse')")
    for ends in ("clamped-clamped", "pinned-pinned", "clamped-pinned"):
        _choose(page, "ends", ends)
        scene = Scene(ustar=-3.0, modes=4, ends=ends)
        top = _top_eigenvalue(scene)
        assert _number(page, "growth-rate") == pytest.approx(top.real, rel=1e-5)
        assert _number(page, "frequency") == pytest.approx(abs(top.imag), rel=1e-5)
        assert f"--ends {ends} " in _text(page, "command")
    onset = critical_velocity(scene)
    page.wait_for_function(f"u => Math.abs(parseFloat(({FIND})(document, 'onset-ustar')"
                           f"?.textContent) - u) < 1e-4 * Math.abs(u)", arg=onset.ustar,
                           timeout=20000)
    assert _number(page, "onset-ustar") == pytest.approx(onset.ustar, rel=1e-5)
    _choose(page, "direction", "forward")
    assert _number(page, "growth-rate") == pytest.approx(
        _top_eigenvalue(scene.replace(ustar=3.0)).real, rel=1e-5)
    _set(page, "ustar", "-2")                                  # the sign said twice
    with pytest.raises(ValueError) as refused:
        Scene.from_dict({"ustar": -2.0, "direction": "forward"})
    assert _text(page, "error") == str(refused.value)


def test_an_analysis_refusing_the_configuration_shows_its_message(page, server, tmp_path):
    """The grazing and fold curves are of contact-free cycles and refuse a scene with the
    contact law on (here from a scene file): the page shows the library's message
    (curves_view called directly), not a traceback."""
    from fsicas.explore.compute import curves_view
    _open(page, server, ustar=3, modes=4)
    touching = tmp_path / "touching.toml"
    touching.write_text("ustar = 3.0\nmodes = 4\ncontact = true\n")
    _load(page, touching)
    with pytest.raises(ValueError) as refused:
        curves_view(load_scene(touching), 40)
    page.get_by_role("button", name="grazing and fold curves").click()
    status = f"() => ({FIND})(document, 'curves-status').textContent"
    page.wait_for_function(f"{status}.startsWith('error')", timeout=60000)
    assert _text(page, "curves-status") == f"error: {refused.value}"
    assert "Traceback" not in _text(page, "curves-status")


def test_stability_flips_at_the_onset_the_library_reports(page, server):
    onset = critical_velocity(Scene())
    _open(page, server, ustar=0.98 * onset.ustar)
    assert _text(page, "stability") == "stable"
    page.locator("[data-testid=onset-ustar]").wait_for(timeout=20000)
    assert _text(page, "onset-kind") == onset.kind == "flutter"
    assert _number(page, "onset-ustar") == pytest.approx(onset.ustar, rel=1e-5)
    _set(page, "ustar", f"{1.02 * onset.ustar:.6g}")
    assert _text(page, "stability") == "unstable"
    assert _number(page, "growth-rate") > 0


def test_invalid_input_is_refused_with_the_library_message(page, server):
    _open(page, server)
    with pytest.raises(ValueError) as refused:
        Scene(mstar=-1.0)
    _set(page, "mstar", "-1")
    assert _text(page, "error") == str(refused.value)
    assert _text(page, "stability") == "stable"                  # the last valid view stays
    _set(page, "mstar", "1")
    assert _text(page, "error") == ""
    _set(page, "modes", "ten")
    assert _text(page, "error") == "modes must be an integer, got 'ten'"
    _set(page, "modes", "10")
    assert _text(page, "error") == ""
    with pytest.raises(ValueError) as refused:
        Scene(slenderness=0.1)
    _set(page, "slenderness", "0.1")                             # with Euler-Bernoulli
    assert _text(page, "error") == str(refused.value)
    page.get_by_label("beam", exact=True).select_option("timoshenko")
    page.wait_for_function(f"() => ({FIND})(document, 'command').textContent"
                           ".includes('--beam timoshenko --slenderness 0.1')")
    assert _text(page, "error") == ""
    assert _number(page, "growth-rate") == pytest.approx(linear_stability(
        Scene(beam="timoshenko", slenderness=0.1)).eigenvalues[0].real, rel=1e-5)


def test_the_state_is_in_the_url_and_the_map_click_moves_the_point(page, server):
    _open(page, server, mstar=2, ustar=3, modes=8)
    scene = Scene(mstar=2.0, ustar=3.0, modes=8)
    assert _number(page, "growth-rate") == pytest.approx(
        linear_stability(scene).eigenvalues[0].real, rel=1e-5)
    assert "--mstar 2 --ustar 3 " in _text(page, "command")
    _set(page, "hstar", "0.12")
    page.wait_for_function("() => location.search.includes('hstar=0.12')")
    canvas = page.locator(".bk-Canvas").nth(2)         # the map: the third figure
    box = canvas.bounding_box()
    canvas.click(position={"x": box["width"] / 2, "y": box["height"] / 2})
    page.wait_for_function("() => location.search.indexOf('mstar=2&') < 0")
    mstar = float(page.url.split("mstar=")[1].split("&")[0])
    assert 0.3 < mstar < 30 and mstar != 2.0


#: The (start, end) of the boundary map's U* axis as the browser fitted it.
MAP_RANGE = """() => { const plot = [...Bokeh.documents[0]._all_models.values()].find(
  m => m.title?.text?.startsWith?.("stability boundary"));
  return [plot.y_range.start, plot.y_range.end]; }"""


def _map_range(page, low: float, high: float) -> tuple:
    """The map's U* axis once it lies within [low, high] (the browser fits it after the
    data arrive)."""
    page.wait_for_function(f"() => {{ const [a, b] = ({MAP_RANGE})(); "
                           f"return a >= {low} && b <= {high} && a < b; }}", timeout=60000)
    return tuple(page.evaluate(MAP_RANGE))


def test_the_map_axis_follows_the_current_point_up_and_down(page, server):
    """Without a boundary the map's U* axis is fitted to the current point: it grows
    with U* and shrinks back."""
    _open(page, server, ustar=30)
    start, end = _map_range(page, 20, 40)
    assert start <= 30 <= end
    _set(page, "ustar", "3")
    start, end = _map_range(page, 0, 5)
    assert start <= 3 <= end


@pytest.mark.slow
def test_the_map_axis_shrinks_when_the_boundary_moves_down(page, server):
    """The U* axis fitted to each new boundary (``boundary_view`` of the scene called
    directly): it shrinks when the boundary moves down."""
    from fsicas.explore.compute import boundary_view
    tops, ends = {}, []
    for hstar in ("0.1", "0.2"):
        if hstar == "0.1":
            _open(page, server, ustar=2, modes=4)
        else:
            _set(page, "hstar", hstar)
        points = boundary_view(Scene(ustar=2.0, modes=4, hstar=float(hstar)))["points"]
        tops[hstar] = max(p["ustar_crit"] for p in points if p.get("ustar_crit"))
        page.get_by_role("button", name="compute the map").click()
        page.wait_for_function(f"() => ({FIND})(document, 'boundary-status').textContent"
                               " === 'done'", timeout=120000)
        start, end = _map_range(page, 0, 1.3 * tops[hstar])
        assert end >= tops[hstar] and start <= 2.0
        ends.append(end)
    assert tops["0.2"] < 0.9 * tops["0.1"]                 # the boundary moved down
    assert ends[1] < ends[0]                               # and the axis with it


def test_instant_tier_latency_in_the_browser(page, server):
    """From a change of U* to the redrawn growth rate (N = 10); printed, not asserted."""
    _open(page, server)
    times = [page.evaluate(LATENCY, ["ustar", f"{u:.3f}", "growth-rate"])
             for u in np.linspace(4.0, 6.0, 9)]
    assert all(t > 0 for t in times), times
    print(f"\ninstant tier latency (ms): median {statistics.median(times):.0f}, "
          f"max {max(times):.0f}, N = 10")


def test_the_map_runs_in_the_background_and_cancels_and_the_view_exports(page, server):
    _open(page, server, ustar=4.5)
    page.get_by_role("button", name="compute the map").click()
    page.wait_for_function(f"() => ({FIND})(document, 'boundary-status').textContent"
                           ".startsWith('computing')")
    _set(page, "ustar", "4.6")                              # the page answers meanwhile
    assert _number(page, "growth-rate") == pytest.approx(
        linear_stability(Scene(ustar=4.6)).eigenvalues[0].real, rel=1e-5)
    page.get_by_role("button", name="cancel", exact=True).click()
    page.wait_for_function(f"() => ({FIND})(document, 'boundary-status').textContent"
                           " === 'cancelled'")
    exported = _export(page)
    assert exported["scene"]["ustar"] == 4.6
    assert exported["boundary"] is None                           # cancelled: not computed
    assert exported["instant"]["growth_rate"] == pytest.approx(_number(page, "growth-rate"),
                                                               rel=1e-5)
    assert exported["command"] == _text(page, "command")


def test_a_time_run_in_the_background_shows_the_library_outcome(page, server):
    scene = Scene(ustar=4.0, zeta=0.01)
    _open(page, server, ustar=4, zeta=0.01)
    page.locator("[data-testid=t-end]").fill("5")
    page.locator("[data-testid=t-end]").press("Enter")             # sent before the click
    page.get_by_role("button", name="time run").click()
    page.locator("[data-testid=run-outcome]").wait_for(timeout=60000)
    run = run_case(scene, 5.0)
    assert _text(page, "run-outcome") == run.outcome.outcome
    assert _text(page, "run-status") == run.status
    assert "fsicas simulate --mstar 1 --ustar 4 " in _text(page, "run-command")
    exported = _export(page)
    assert exported["run"]["outcome"] == run.outcome.outcome
    assert len(exported["run"]["tip"]) == len(exported["run"]["t"]) > 10


def test_a_physical_preset_gives_hz_and_l_per_min_of_the_library(page, server):
    _open(page, server)
    page.get_by_label("physical preset").select_option("soft_palate")
    page.locator("[data-testid=flow]").wait_for(timeout=30000)
    physical = load_physical("soft_palate")
    scene = physical.scene(physical.flow)
    assert float(_text(page, "flow").split()[0]) == pytest.approx(
        scene.scales.l_per_min(scene.ustar), rel=1e-4)
    page.locator("[data-testid=onset-ustar]").wait_for(timeout=30000)
    onset = critical_velocity(scene)
    hz = page.locator("text=physical:").inner_text()
    assert f"{scene.scales.l_per_min(onset.ustar):.4g} L/min" in hz
    assert f"{scene.scales.hz(onset.omega):.4g} Hz" in hz
    page.wait_for_function("() => location.search.includes('preset=soft_palate')")


def _preset_with(name: str = "soft_palate", **values) -> Physical:
    """The preset ``name`` with ``values`` (texts with units) in its [physical] table,
    read by the library."""
    preset = load_physical(name)
    return Physical.from_table({**preset.raw, **values}, name, preset.description,
                               preset.scene_fields)


def test_physical_inputs_with_units_are_converted_by_the_library(page, server):
    _open(page, server)
    page.get_by_label("physical preset").select_option("soft_palate")
    page.locator("[data-testid=flow]").wait_for(timeout=30000)
    assert page.locator("[data-testid=phys-E]").input_value() == "3 kPa"
    assert page.locator("[data-testid=phys-flow]").input_value() == "20 L/min"
    _set(page, "phys-E", "4 kPa")
    _set(page, "phys-flow", "25 L/min")
    scene = _preset_with(E="4 kPa").scene(parse_flow("25 L/min"))
    assert float(_text(page, "flow").split()[0]) == pytest.approx(25.0, rel=1e-4)
    assert _number(page, "growth-rate") == pytest.approx(
        linear_stability(scene).eigenvalues[0].real, rel=1e-5)
    assert f"--mstar {scene.mstar:g} --ustar {scene.ustar:g} " in _text(page, "command")
    page.wait_for_function("() => location.search.includes('E=4')")
    with pytest.raises(ValueError) as refused:
        _preset_with(E="-3 kPa")
    _set(page, "phys-E", "-3 kPa")
    assert _text(page, "error") == str(refused.value)
    _set(page, "phys-E", "4 kPa")
    assert _text(page, "error") == ""
    with pytest.raises(ValueError) as refused:
        parse_flow("20 L", "airflow")
    _set(page, "phys-flow", "20 L")
    assert _text(page, "error") == str(refused.value)
    assert _number(page, "growth-rate") == pytest.approx(                   # the view stays
        linear_stability(scene).eigenvalues[0].real, rel=1e-5)


def test_the_limit_cycle_branch_in_the_background_is_the_library_one(page, server):
    _open(page, server)
    status = f"() => ({FIND})(document, 'lco-status').textContent"
    page.get_by_role("button", name="limit cycles", exact=True).click()
    page.wait_for_function(f"{status}.startsWith('computing')")
    page.get_by_role("button", name="cancel cycles").click()
    page.wait_for_function(f"{status} === 'cancelled'")
    page.get_by_role("button", name="limit cycles", exact=True).click()
    page.locator("[data-testid=lco-contact]").wait_for(timeout=180000)
    branch = cycle_branch(Scene(), ustar_max=20.0)
    assert _text(page, "lco-status") == branch.status == "contact"
    assert int(_text(page, "lco-points")) == len(branch.points)
    assert _number(page, "lco-contact") == pytest.approx(branch.contact.ustar, rel=1e-4)
    assert "fsicas lco --mstar 1 --ustar 5 " in _text(page, "lco-command")
    exported = _export(page)["cycles"]
    assert exported["contact"]["ustar"] == pytest.approx(branch.contact.ustar, rel=1e-9)
    assert [p["stable"] for p in exported["points"]] == [p.stable for p in branch.points]


def _load(page, path: Path) -> None:
    """Load the scene file ``path`` in the page and wait until it has answered (its
    command line or its error changed)."""
    state = f"() => ['command', 'error'].map(i => ({FIND})(document, i).textContent).join('|')"
    old = page.evaluate(state)
    page.locator("input[type=file]").set_input_files(str(path))
    page.wait_for_function(f"old => ({state})() !== old", arg=old, timeout=30000)


def test_a_scene_file_loads_as_the_cli_reads_it_and_a_bad_one_is_refused(page, server, tmp_path,
                                                                          monkeypatch):
    _open(page, server)
    mine = tmp_path / "mine.toml"
    mine.write_text("mstar = 2.0\nustar = 3.0\nk0 = 0.5\nmodes = 8\nzeta = 0.01\n")
    _load(page, mine)
    scene = load_scene(mine)
    page.wait_for_function(f"() => ({FIND})(document, 'scene-file').textContent.length > 0")
    assert _text(page, "scene-file") == "mine.toml (scene file)"
    assert _number(page, "growth-rate") == pytest.approx(
        linear_stability(scene).eigenvalues[0].real, rel=1e-5)
    assert _text(page, "command") == "fsicas eig --scene mine.toml --json"
    _set(page, "ustar", "3.5")                                   # the page's values win
    assert _text(page, "command") == "fsicas eig --scene mine.toml --ustar 3.5 --json"
    space = {}
    monkeypatch.chdir(tmp_path)                                  # where the file is
    exec(_text(page, "python"), space)                           # the page's Python lines
    assert space["scene"] == scene.replace(ustar=3.5)
    assert _number(page, "growth-rate") == pytest.approx(
        space["stability"].eigenvalues[0].real, rel=1e-5)
    _load(page, mine)                                            # again: the file's values
    assert _text(page, "command") == "fsicas eig --scene mine.toml --json"
    for name, text in (("bad.toml", "mstar = [\n"), ("odd.toml", "mstar = 2.0\nspeed = 3\n"),
                       ("neg.toml", "mstar = -1.0\n")):
        (tmp_path / name).write_text(text)
        with pytest.raises(ValueError) as refused:
            load_scene(tmp_path / name)
        _load(page, tmp_path / name)
        assert _text(page, "error") == str(refused.value).replace(f"{tmp_path}/", "")
        assert "Traceback" not in _text(page, "error")
    assert _number(page, "growth-rate") == pytest.approx(                    # the view stays
        linear_stability(scene).eigenvalues[0].real, rel=1e-5)
    physical = tmp_path / "palate.toml"                          # as fsicas onset --physical
    physical.write_text('preset = "soft_palate"\n[physical]\nE = "4 kPa"\nflow = "25 L/min"\n')
    _load(page, physical)
    read = load_physical(str(physical))
    assert _text(page, "scene-file") == "palate.toml (physical file)"
    assert page.locator("[data-testid=phys-E]").input_value() == "4 kPa"
    assert float(_text(page, "flow").split()[0]) == pytest.approx(25.0, rel=1e-4)
    assert _number(page, "growth-rate") == pytest.approx(
        linear_stability(read.scene(read.flow)).eigenvalues[0].real, rel=1e-5)


def test_a_loaded_file_is_in_the_address_and_the_preset_menu_names_it(page, server, browser,
                                                                      tmp_path):
    """The address holds a loaded file's values (not its path): reopened in a new tab,
    with the file gone, it shows the file's scene as ``load_scene`` / ``load_physical``
    read it; the menu shows the preset a physical file is, else "from file"."""
    _open(page, server)
    mine = tmp_path / "mine.toml"                  # k0 and the per-mode zeta: not boxes
    mine.write_text("mstar = 2.0\nustar = 3.0\nk0 = 0.5\nmodes = 4\n"
                    "zeta = [0.01, 0.02, 0.03, 0.04]\n")
    scene = load_scene(mine)
    _load(page, mine)
    assert page.get_by_label("physical preset").input_value() == "from file"
    page.wait_for_function("() => location.search.includes('scene=')")
    url = page.url
    assert str(tmp_path) not in url and "scenefile=mine.toml" in url
    mine.unlink()
    other = browser.new_page()
    try:
        other.goto(url)
        other.wait_for_function(f"() => ({FIND})(document, 'scene-file')?.textContent"
                                ".includes('from the address')", timeout=30000)
        command = "fsicas eig --scene mine.toml --json"     # the label may come first
        other.wait_for_function(f"c => ({FIND})(document, 'command').textContent === c",
                                arg=command, timeout=30000)
        assert _text(other, "command") == command
        assert _number(other, "growth-rate") == pytest.approx(
            linear_stability(scene).eigenvalues[0].real, rel=1e-5)
    finally:
        other.close()
    same = tmp_path / "same.toml"                  # a physical file of the preset's values
    same.write_text('preset = "soft_palate"\n[physical]\n')
    _load(page, same)
    page.wait_for_function(f"() => ({FIND})(document, 'scene-file').textContent"
                           ".includes('same.toml')")
    assert page.get_by_label("physical preset").input_value() == "soft_palate"
    assert "the preset soft_palate" in _text(page, "scene-file")
    changed = tmp_path / "palate.toml"
    changed.write_text('preset = "soft_palate"\n[physical]\nE = "4 kPa"\nflow = "25 L/min"\n')
    _load(page, changed)
    read = load_physical(str(changed))
    assert page.get_by_label("physical preset").input_value() == "from file"
    page.wait_for_function("() => location.search.includes('scenefile=palate.toml')")
    url = page.url
    other = browser.new_page()
    try:
        other.goto(url)
        other.wait_for_function(f"() => ({FIND})(document, 'scene-file')?.textContent"
                                ".includes('from the address')", timeout=30000)
        assert other.locator("[data-testid=phys-E]").input_value() == "4 kPa"
        assert _number(other, "growth-rate") == pytest.approx(
            linear_stability(read.scene(read.flow)).eigenvalues[0].real, rel=1e-5)
    finally:
        other.close()


def test_the_densities_poisson_ratio_and_viscosity_are_physical_inputs_too(page, server):
    _open(page, server)
    page.get_by_label("physical preset").select_option("harvester")
    page.locator("[data-testid=flow]").wait_for(timeout=30000)
    shown = {k: page.locator(f"[data-testid=phys-{k}]").input_value()
             for k in ("nu", "rho_s", "rho_f", "viscosity")}
    assert shown == {"nu": "0.38", "rho_s": "1390 kg/m^3", "rho_f": "1.2 kg/m^3",
                     "viscosity": "1.8e-5 Pa*s"}
    values = {"nu": "0.3", "rho_s": "1.2 g/cm^3", "rho_f": "1 kg/m^3", "viscosity": "3.6e-5 Pa*s"}
    for key, text in values.items():
        _set(page, f"phys-{key}", text)
    physical = _preset_with("harvester", **values)
    scene = physical.scene(physical.flow)
    assert _number(page, "growth-rate") == pytest.approx(
        linear_stability(scene).eigenvalues[0].real, rel=1e-5)
    assert float(page.locator("[data-testid=friction]").input_value()) == pytest.approx(
        physical.friction(physical.flow)[0], rel=1e-5)        # f from the viscosity's Re
    assert f"--mstar {scene.mstar:g} " in _text(page, "command")
    page.wait_for_function("() => location.search.includes('rho_s=1.2')")
    for key, text in (("rho_f", "-1 kg/m^3"), ("viscosity", "2 m")):
        with pytest.raises(ValueError) as refused:
            _preset_with("harvester", **{**values, key: text})
        _set(page, f"phys-{key}", text)
        assert _text(page, "error") == str(refused.value)
        _set(page, f"phys-{key}", values[key])
        assert _text(page, "error") == ""


def _wav(page) -> np.ndarray:
    """The samples of the page's ``<audio>`` element (its WAV, served as a data: URL),
    as floats in [-1, 1]."""
    import base64
    import io
    import wave
    src = page.locator("audio").get_attribute("src")
    assert src.startswith("data:audio/wav;base64,"), src[:40]
    with wave.open(io.BytesIO(base64.b64decode(src.split(",", 1)[1]))) as w:
        return np.frombuffer(w.readframes(w.getnframes()), dtype="<i2") / 32767


def _snore(page, server, t_end: str = "25") -> dict:
    """The harvester just past its supercritical onset (U* = 3.5), run to ``t_end`` on
    the page until it snores: the exported sound."""
    _open(page, server)
    page.get_by_label("physical preset").select_option("harvester")
    page.locator("[data-testid=flow]").wait_for(timeout=30000)
    _set(page, "ustar", "3.5")
    box = page.locator("[data-testid=t-end]")
    box.fill(t_end)
    box.press("Enter")                                            # sent before the click
    page.get_by_role("button", name="time run").click()
    page.locator("[data-testid=sound-pitch]").wait_for(timeout=180000)
    assert _text(page, "run-outcome") == "lco"
    return _export(page)["run"]["sound"]


def test_the_snore_plays_with_its_spectrum_of_the_library(page, server):
    """The harvester's cycle: the page plays its sound and shows the spectrum of it,
    which is that of the WAV it plays, computed by the library (line_spectrum) and by a
    plain FFT; a bad t_end is refused."""
    import scipy.signal
    from fsicas.timedomain.sound import P_REF, line_spectrum
    _open(page, server)
    t_end = page.locator("[data-testid=t-end]")
    t_end.fill("-1")
    t_end.press("Enter")
    page.get_by_role("button", name="time run").click()
    page.wait_for_function(f"() => ({FIND})(document, 'run-status').textContent"
                           ".startsWith('error')")
    assert "t_end must be in (0, 1000], got -1.0" in _text(page, "run-status")
    assert page.locator("audio").count() == 0 or not page.locator("audio").is_visible()
    sound = _snore(page, server)
    shown = np.array(sound["spectrum"]["spl_db"])
    pressure = _wav(page) * sound["peak_pa"]                      # back to Pa
    hz, db = line_spectrum(pressure, sound["sample_rate_hz"], 5000.0)
    assert np.array(sound["spectrum"]["hz"]) == pytest.approx(hz)
    strong = db > db.max() - 60                                    # above the WAV's rounding
    assert shown[strong] == pytest.approx(db[strong], abs=0.05)
    window = scipy.signal.get_window("hann", pressure.size)        # periodic, as periodogram
    lines = np.abs(np.fft.rfft((pressure - pressure.mean()) * window)) ** 2
    plain = 10 * np.log10(2 * lines / window.sum() ** 2 / P_REF ** 2)
    j = int(np.argmax(shown))
    assert shown[j] == pytest.approx(plain[j], abs=0.05)
    assert hz[j] == pytest.approx(float(_text(page, "sound-pitch").split()[0]), abs=1.0)


@pytest.mark.slow
@pytest.mark.slow
def test_a_physical_run_without_a_cycle_says_why_it_has_no_snore(page, server):
    """The soft palate at its default airflow reaches the wall (``run_case`` called
    directly): no audio, and the page says why (no settled cycle to loop)."""
    page.goto(server + "?preset=soft_palate")
    page.locator("[data-testid=command]").wait_for(timeout=30000)
    page.get_by_role("button", name="time run").click()
    page.locator("[data-testid=run-outcome]").wait_for(timeout=120000)
    read = load_physical("soft_palate")
    outcome = run_case(read.scene(read.flow), 20.0).to_json()["outcome"]
    assert _text(page, "run-outcome") == outcome == "contact"
    assert _text(page, "sound-none").startswith(
        "none: the run's outcome is contact, not a settled cycle to loop.")
    assert page.locator("audio").count() == 0 or not page.locator("audio").is_visible()


def test_the_snore_python_lines_give_the_page_snore(page, server):
    """The Python lines the page shows under the snore, run here, give its spectrum and
    pitch."""
    sound = _snore(page, server)
    space = {}
    exec(_text(page, "sound-python"), space)
    assert space["sound"].fundamental_hz == pytest.approx(sound["fundamental_hz"], rel=1e-9)
    assert space["spl_db"] == pytest.approx(np.array(sound["spectrum"]["spl_db"]), abs=1e-3)


def _saved(page, title: str, index: int) -> tuple[str, bytes]:
    """The name and content of what the toolbar button ``title`` of figure ``index``
    downloads."""
    with page.expect_download() as download:
        page.locator(f"[title='{title}']").nth(index).click()
    return download.value.suggested_filename, Path(download.value.path()).read_bytes()


def test_each_figure_saves_as_svg_and_png(page, server):
    """The root locus saved as SVG draws one marker per eigenvalue of the library, the
    unstable ones red; the same figure saves as PNG; an empty figure (the map before it
    is computed) as an SVG without markers."""
    import xml.etree.ElementTree as ET
    from fsicas.explore.figures import STABLE_COLOR, SVG_TOOL, UNSTABLE_COLOR
    _open(page, server, ustar=6)
    lam = linear_stability(Scene(ustar=6.0)).eigenvalues
    buttons = page.locator(f"[title='{SVG_TOOL}']")               # one a figure shown, not
    assert [buttons.nth(i).is_visible() for i in range(buttons.count())] == [True] * 5  # hidden
    name, svg = _saved(page, SVG_TOOL, 1)                         # figures: mode, locus, map
    assert name == "eigenvalues.svg"
    paths = [e.attrib for e in ET.fromstring(svg).iter("{http://www.w3.org/2000/svg}path")]
    rgb = lambda color: "rgb({},{},{})".format(*bytes.fromhex(color[1:]))
    markers = [p["fill"] for p in paths if " A 3.5 3.5 " in p.get("d", "")]
    assert markers.count(rgb(UNSTABLE_COLOR)) == np.sum(lam.real > 0) == 2
    assert markers.count(rgb(STABLE_COLOR)) == np.sum(lam.real <= 0)
    assert b"growth rate" in svg                                   # the axis label, as text
    name, png = _saved(page, "Save", 1)
    assert name == "eigenvalues.png" and png.startswith(b"\x89PNG")
    name, svg = _saved(page, SVG_TOOL, 2)
    assert name == "boundary.svg"
    assert not [p for p in ET.fromstring(svg).iter("{http://www.w3.org/2000/svg}path")
                if " A 3" in p.get("d", "")]


def _through_contact(page, points: str) -> None:
    """Ask for the limit cycles on through contact, at most ``points`` impacting ones."""
    page.locator("input[type=checkbox]").check()                # "on through contact"
    box = page.locator("[data-testid=impact-points]")
    box.fill(points)
    box.press("Enter")                                           # sent before the click
    page.get_by_role("button", name="limit cycles", exact=True).click()


@pytest.mark.slow
def test_the_branch_through_contact_is_that_of_its_command(page, server, tmp_path):
    """M* = 1, ζ = 0.01, N = 4 (docs/cycles.md): five impacting cycles past the first
    contact; the page's command line, run, gives the same branch (about 2 minutes)."""
    _open(page, server, zeta=0.01, modes=4)
    _through_contact(page, "5")
    page.locator("[data-testid=impact-status]").wait_for(timeout=900000)
    command = _text(page, "lco-command")
    assert command.endswith("--through-contact --impact-points 5 --json")
    done = subprocess.run([sys.executable, "-m", "fsicas.cli", *command.split()[1:]],
                          capture_output=True, text=True, cwd=tmp_path, timeout=900,
                          env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert done.returncode == 0, done.stderr
    cli = json.loads(done.stdout)["impacting"]
    shown = _export(page)["cycles"]["impacting"]
    assert _text(page, "impact-status") == shown["status"] == cli["status"]
    assert int(_text(page, "impact-count")) == len(cli["points"]) == 5
    for mine, theirs in zip(shown["points"], cli["points"]):
        assert mine["ustar"] == pytest.approx(theirs["ustar"], rel=1e-6)
        assert mine["tip_amplitude"] == pytest.approx(theirs["tip_amplitude"], rel=1e-5)
        assert (mine["impacts"], mine["stable"]) == (theirs["impacts"], theirs["stable"])


def _curves(page, points: str) -> None:
    """Ask for the grazing and fold curves, at most ``points`` points per direction."""
    box = page.locator("[data-testid=curve-points]")
    box.fill(points)
    box.press("Enter")                                           # sent before the click
    page.get_by_role("button", name="grazing and fold curves").click()


@pytest.mark.parametrize("ask, testid, what", [
    (_through_contact, "lco-status", "impacting cycles"),
    (_curves, "curves-status", "curve points")])
def test_the_heavy_jobs_refuse_a_bad_count_and_cancel(page, server, ask, testid, what):
    """The branch through contact and the curves: a count that is not a whole number is
    refused by the page, one out of range by the job (the library's ValueError); a job
    cancels."""
    _open(page, server, modes=4)
    status = f"() => ({FIND})(document, '{testid}').textContent"
    ask(page, "many")
    page.wait_for_function(f"{status}.startsWith('error')")
    assert _text(page, testid) == f"error: the {what} must be an integer, got 'many'"
    ask(page, "0")
    page.wait_for_function(f"{status}.includes('[1,')")
    assert _text(page, testid) == f"error: the {what} must be an integer in [1, 1000], got 0"
    ask(page, "10")
    page.wait_for_function(f"{status}.startsWith('computing')")
    cancel = "cancel cycles" if testid == "lco-status" else "cancel curves"
    page.get_by_role("button", name=cancel).click()
    page.wait_for_function(f"{status} === 'cancelled'")


@pytest.mark.slow
def test_the_grazing_and_fold_curves_are_those_of_their_command(page, server, tmp_path):
    """N = 4 over M* in [0.1, 100], at most 10 points per direction: the curves on the
    map are those of the page's own `fsicas grazing` line, run (a few minutes)."""
    _open(page, server, modes=4)
    _curves(page, "10")
    page.locator("[data-testid=curves-grazing]").wait_for(timeout=1200000)
    command = _text(page, "curves-command")
    assert " --mstar 0.1:100:19 --max-points 10 --json" in command
    done = subprocess.run([sys.executable, "-m", "fsicas.cli", *command.split()[1:]],
                          capture_output=True, text=True, cwd=tmp_path, timeout=1200,
                          env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert done.returncode == 0, done.stderr
    cli = json.loads(done.stdout)
    shown = _export(page)["curves"]
    assert shown["seeds"] == pytest.approx(cli["seeds"], rel=1e-9)
    for kind in ("grazing", "fold"):
        assert int(_text(page, f"curves-{kind}")) == len(shown[kind])
        points = [(m, u) for c in shown[kind] for m, u in zip(c["mstar"], c["ustar"])]
        assert len(points) == len(cli[kind])
        assert points == pytest.approx([(p["mstar"], p["ustar"]) for p in cli[kind]], rel=1e-6)
