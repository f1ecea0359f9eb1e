"""The viewer: the HTML page (self-contained, bounded, clear errors) and the page in a real browser.

The browser tests drive headless Chromium (Debian's ``chromium`` package; ``.ci/run`` installs
it) through the DevTools protocol over a pipe (``--remote-debugging-pipe``: JSON messages ending
in NUL on file descriptors 3 and 4), load the page from a file:// URL once per mode and inspect
the screenshots; they skip, saying why, when no browser is installed.
"""

from __future__ import annotations

import base64
import io
import json
import os
import queue
import re
import shutil
import subprocess
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import g1patch
from g1patch.cli import main
from g1patch.io.network_file import save_network
from g1patch.viewer import MODES, VENDORED_THREE_VERSION, ViewTooLargeError, view_html, write_view

DATA = Path(__file__).resolve().parents[1] / "src" / "g1patch" / "data"
#: http(s) URLs that may appear in a page: XML namespace names inside three.js, never fetched
NAMESPACES = {"http://www.w3.org/1999/xhtml", "http://www.w3.org/2000/svg"}
WINDOW = (1000, 720)


@pytest.fixture(scope="module")
def cube() -> g1patch.Surface:
    return g1patch.smooth(DATA / "cube.obj", method="gregory")


@pytest.fixture(scope="module")
def cube_page(cube: g1patch.Surface, tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_view(tmp_path_factory.mktemp("view") / "cube.html", cube.network)


@pytest.fixture(scope="module")
def creased() -> g1patch.Surface:
    """The corner method on the cube: G1 at corners only, every edge creased (a visible
    deviation)."""
    return g1patch.smooth(DATA / "cube.obj", method="corner")


# ----------------------------------------------------------------------------- the page


def _embedded(page: str, name: str, dtype: Any) -> np.ndarray:
    match = re.search(
        rf'<script type="application/octet-stream" id="g1-{name}">([^<]*)</script>', page
    )
    assert match is not None, name
    return np.frombuffer(base64.b64decode(match.group(1)), dtype=dtype)


def _meta(page: str) -> dict[str, Any]:
    match = re.search(r'<script type="application/json" id="g1-meta">(.*?)</script>', page, re.S)
    assert match is not None
    return json.loads(match.group(1))


def test_page_is_self_contained(cube_page: Path) -> None:
    page = cube_page.read_text(encoding="utf-8")
    urls = set(re.findall(r"https?://[^\s\"'<>)\\]+", page))
    assert urls <= NAMESPACES, urls - NAMESPACES
    assert not re.search(
        r"<(script|link|img|iframe)[^>]+(src|href)=", page
    )  # nothing loaded by reference
    imports = json.loads(
        re.search(r'<script type="importmap">(.*?)</script>', page, re.S).group(1)
    )["imports"]
    assert set(imports) == {"three", "three/addons/controls/OrbitControls.js"}
    assert all(url.startswith("data:text/javascript;base64,") for url in imports.values())
    three = base64.b64decode(imports["three"].split(",", 1)[1]).decode()
    assert f'const t="{VENDORED_THREE_VERSION.split(".")[1]}"' in three[:400]  # the pinned release
    assert "Copyright © 2010-2024 three.js authors" in page  # its licence travels with it
    assert "@@" not in page  # every field filled


def test_page_holds_the_exact_samples(cube: g1patch.Surface, cube_page: Path) -> None:
    page = cube_page.read_text(encoding="utf-8")
    meta = _meta(page)
    n, r = cube.n_patches, meta["resolution"]
    assert (n, r, meta["up"]) == (6, 17, "y") and meta["triangles"] == 2 * 16**2 * 6
    positions = _embedded(page, "positions", np.float32).reshape(n, r, r, 3) + np.array(
        meta["centre"]
    )
    normals = _embedded(page, "normals", np.float32).reshape(n, r, r, 3)
    grid = np.linspace(0, 1, r)
    exact = cube.patches.evaluate_grid(grid, grid)
    assert np.abs(positions - exact).max() < 1e-6
    assert meta["radius"] == pytest.approx(
        np.linalg.norm(exact - meta["centre"], axis=-1).max(), rel=1e-6
    )
    du, dv = (
        cube.patches.evaluate_grid(grid, grid, 1, 0),
        cube.patches.evaluate_grid(grid, grid, 0, 1),
    )
    unit = np.cross(du, dv)
    unit /= np.linalg.norm(unit, axis=-1, keepdims=True)
    assert np.abs(normals - unit).max() < 1e-6
    sides = _embedded(page, "sides", np.float32).reshape(n, 4)
    assert (sides >= 0).all() and sides.max() < 1e-9  # every side shared, exactly G1
    assert _embedded(page, "seams", np.float32).size == 0
    assert meta["exact"] and meta["verdict"].startswith("exactly G1")


def test_page_size_is_bounded(cube_page: Path) -> None:
    # three.js (~0.95 MB as base64) and 32 bytes of base64 per sample: 6 × 17² samples
    size = cube_page.stat().st_size
    assert 0.9e6 < size < 1.0e6 + 32 * 6 * 17**2 + 20_000


def test_seams_are_embedded_as_lines() -> None:
    mesh = g1patch.read(DATA / "cube.obj")
    surface = g1patch.smooth(mesh, method="gregory", sharp_angle=30.0)
    page = view_html(surface.network)
    meta = _meta(page)
    seams = _embedded(page, "seams", np.float32).reshape(-1, 2, 3)
    assert surface.network.n_seams and len(seams) == meta["seamSegments"] == 12 * (
        meta["resolution"] - 1
    )
    sides = _embedded(page, "sides", np.float32).reshape(-1, 4)
    assert ((sides == -1).sum(), surface.check().seam_edges) == (24, 12)


def test_budget_refuses_large_pages_unless_forced(cube: g1patch.Surface, tmp_path: Path) -> None:
    target = tmp_path / "big.html"
    with pytest.raises(
        ViewTooLargeError,
        match=r"6 patches at 500 samples a side .* 2.99 M triangles .* budget of 2 M",
    ):
        write_view(target, cube.network, resolution=500)
    assert not list(tmp_path.iterdir())
    assert isinstance(ViewTooLargeError("x"), g1patch.InputError)
    page = view_html(cube.network, resolution=3)
    assert _meta(page)["resolution"] == 3
    from g1patch.viewer import _resolution

    with pytest.raises(
        ViewTooLargeError,
        match=r"1200000 patches at 2 samples .* 2.4 M triangles \(~180 MB\).*coarsest",
    ):
        _resolution(
            1_200_000, None, False
        )  # above a million patches even the coarsest page is too large
    assert _resolution(1_200_000, None, True) == 2


def test_bad_input_is_one_clear_error(cube: g1patch.Surface, tmp_path: Path) -> None:
    with pytest.raises(g1patch.FormatError, match=r"page\.png.*expected a \.html file name"):
        cube.view(tmp_path / "page.png")
    with pytest.raises(g1patch.InputError, match=r"resolution: expected an integer ≥ 2, got 1"):
        cube.view(tmp_path / "page.html", resolution=1)
    with pytest.raises(g1patch.InputError, match="network: expected a PatchNetwork"):
        view_html("cube.npz")  # type: ignore[arg-type]
    assert not list(tmp_path.iterdir())


def test_surface_view_writes_or_returns_the_page(cube: g1patch.Surface, tmp_path: Path) -> None:
    assert cube.view(tmp_path / "cube.html") == tmp_path / "cube.html"
    assert (tmp_path / "cube.html").read_text(encoding="utf-8").startswith("<!DOCTYPE html>")
    assert cube.view().startswith("<!DOCTYPE html>")
    assert g1patch.api.view(cube.network, tmp_path / "again.htm").exists()


def test_cli_view(
    cube: g1patch.Surface, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    network = tmp_path / "cube.npz"
    save_network(network, cube.network)
    assert main(["view", str(network), "-o", str(tmp_path / "cube.html")]) == 0
    out = capsys.readouterr().out
    assert re.search(r"wrote a viewer of 6 patches, 3072 triangles \(.* MB\) -> .*cube\.html", out)
    assert (
        main(["view", str(network), "-o", str(tmp_path / "big.html"), "--resolution", "600"]) == 2
    )
    error = capsys.readouterr().err.strip()
    assert error.startswith("g1patch: error: ") and "--force" in error and "\n" not in error
    assert main(["view", str(tmp_path / "missing.npz"), "-o", str(tmp_path / "x.html")]) == 2
    assert "missing.npz" in capsys.readouterr().err
    (tmp_path / "mesh.obj").write_text("v 0 0 0\n")
    assert main(["view", str(tmp_path / "mesh.obj"), "-o", str(tmp_path / "x.html")]) == 2
    assert "g1patch build" in capsys.readouterr().err
    assert sorted(path.name for path in tmp_path.iterdir()) == ["cube.html", "cube.npz", "mesh.obj"]


# ----------------------------------------------------------------------------- a real browser


def _browser() -> str | None:
    for name in ("chromium", "chromium-browser", "google-chrome", "chrome"):
        found = shutil.which(name)
        if found:
            return found
    return None


class DevTools:
    """Headless Chromium driven over ``--remote-debugging-pipe``: commands in, replies and events
    out."""

    def __init__(self, executable: str, profile: Path) -> None:
        command_read, self._command_write = os.pipe()
        self._reply_read, reply_write = os.pipe()

        def pipes() -> (
            None
        ):  # in the child: the protocol's descriptors 3 (commands) and 4 (replies)
            import fcntl

            commands, replies = (
                fcntl.fcntl(fd, fcntl.F_DUPFD, 10) for fd in (command_read, reply_write)
            )
            os.dup2(commands, 3)
            os.dup2(replies, 4)

        self.process = subprocess.Popen(
            [
                executable,
                "--headless",
                "--remote-debugging-pipe",
                "--no-sandbox",
                "--use-angle=swiftshader",
                "--enable-unsafe-swiftshader",
                "--no-first-run",
                "--no-default-browser-check",
                "--disable-extensions",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--hide-scrollbars",
                "--mute-audio",
                f"--user-data-dir={profile}",
                f"--window-size={WINDOW[0]},{WINDOW[1]}",
                "about:blank",
            ],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            preexec_fn=pipes,
            close_fds=False,
        )
        os.close(command_read)
        os.close(reply_write)
        self._next = 0
        self._replies: queue.Queue[dict[str, Any]] = queue.Queue()
        self.events: list[dict[str, Any]] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()
        self._stderr: list[bytes] = []
        threading.Thread(
            target=lambda: self._stderr.extend(self.process.stderr), daemon=True
        ).start()  # type: ignore[arg-type]
        self.session = ""

    def _read(self) -> None:
        buffer = b""
        with os.fdopen(self._reply_read, "rb", buffering=0) as replies:
            while chunk := replies.read(1 << 20):
                buffer += chunk
                *messages, buffer = buffer.split(b"\0")
                for message in messages:
                    self._replies.put(json.loads(message))

    def send(self, method: str, timeout: float = 60.0, **params: Any) -> dict[str, Any]:
        """Send one command (to the page's session once attached) and wait for its reply."""
        self._next += 1
        message: dict[str, Any] = {"id": self._next, "method": method, "params": params}
        if self.session and not method.startswith("Target."):
            message["sessionId"] = self.session
        os.write(self._command_write, json.dumps(message).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while True:
            try:
                reply = self._replies.get(timeout=max(deadline - time.monotonic(), 0.01))
            except queue.Empty:
                raise TimeoutError(f"no reply to {method} in {timeout} s") from None
            if reply.get("id") == self._next:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply.get("result", {})
            self.events.append(reply)

    def open_page(self) -> None:
        target = self.send("Target.createTarget", url="about:blank")["targetId"]
        self.session = self.send("Target.attachToTarget", targetId=target, flatten=True)[
            "sessionId"
        ]
        for domain in ("Page", "Runtime", "Log", "Network"):
            self.send(f"{domain}.enable")
        self.send(
            "Emulation.setDeviceMetricsOverride",
            width=WINDOW[0],
            height=WINDOW[1],
            deviceScaleFactor=1,
            mobile=False,
        )

    def evaluate(self, expression: str, timeout: float = 60.0) -> Any:
        result = self.send(
            "Runtime.evaluate",
            timeout,
            expression=expression,
            awaitPromise=True,
            returnByValue=True,
        )
        if "exceptionDetails" in result:
            raise RuntimeError(f"{expression}: {result['exceptionDetails']}")
        return result["result"].get("value")

    def close(self) -> None:
        try:
            self.send("Browser.close", timeout=10)
        except (OSError, TimeoutError, RuntimeError):
            pass
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        os.close(self._command_write)


@pytest.fixture(scope="module")
def browser(tmp_path_factory: pytest.TempPathFactory) -> Iterator[DevTools]:
    executable = _browser()
    if executable is None:
        pytest.skip(
            "no Chromium found (apt-get install chromium): the viewer's browser tests need one"
        )
    tools = DevTools(executable, tmp_path_factory.mktemp("chromium-profile"))
    try:
        tools.open_page()
        yield tools
    finally:
        tools.close()


def shoot(browser: DevTools, page: Path, mode: str) -> tuple[np.ndarray, np.ndarray]:
    """Load ``page`` in ``mode`` (its URL hash); the screenshot (H, W, 3) and the canvas's coverage
    (H, W)."""
    from PIL import Image

    browser.send("Page.navigate", url="about:blank")
    browser.send("Page.navigate", url=page.as_uri() + "#" + mode)
    deadline = time.monotonic() + 90
    while browser.evaluate("document.documentElement?.dataset.rendered || ''") != mode:
        message = browser.evaluate("document.getElementById?.('message')?.textContent || ''")
        assert not message, message
        assert time.monotonic() < deadline, f"{page.name}#{mode} did not render in 90 s"
        time.sleep(0.1)
    browser.evaluate(
        "new Promise(done => requestAnimationFrame(() => requestAnimationFrame(done)))"
    )
    shot = base64.b64decode(browser.send("Page.captureScreenshot", format="png")["data"])
    canvas = browser.evaluate("document.querySelector('canvas').toDataURL('image/png')")
    image = np.asarray(Image.open(io.BytesIO(shot)).convert("RGB"))
    alpha = np.asarray(
        Image.open(io.BytesIO(base64.b64decode(canvas.split(",", 1)[1]))).convert("RGBA")
    )[..., 3]
    return image, alpha > 0


def _errors(browser: DevTools) -> list[str]:
    """Console errors, uncaught exceptions and error log entries seen so far."""
    found = []
    for event in browser.events:
        method, params = event.get("method"), event.get("params", {})
        if method == "Runtime.exceptionThrown":
            found.append(json.dumps(params["exceptionDetails"])[:300])
        elif method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert"):
            found.append(
                " ".join(
                    str(arg.get("value", arg.get("description"))) for arg in params.get("args", [])
                )
            )
        elif method == "Log.entryAdded" and params["entry"]["level"] == "error":
            found.append(params["entry"]["text"])
    return found


def _requests(browser: DevTools) -> set[str]:
    return {
        event["params"]["request"]["url"].split(":", 1)[0]
        for event in browser.events
        if event.get("method") == "Network.requestWillBeSent"
    }


def _alternations(row: np.ndarray, covered: np.ndarray) -> int:
    """Light/dark changes along a scanline inside the surface (grey levels split at their
    median)."""
    grey = row[covered].mean(axis=-1)
    if grey.size < 20:
        return 0
    light = grey > 0.5 * (np.percentile(grey, 10) + np.percentile(grey, 90))
    return int(np.count_nonzero(light[1:] != light[:-1]))


SCREENSHOTS = os.environ.get(
    "G1PATCH_SCREENSHOTS"
)  # a folder to keep the screenshots in, for a person to look at


def _keep(image: np.ndarray, name: str) -> None:
    if SCREENSHOTS:
        from PIL import Image

        Path(SCREENSHOTS).mkdir(parents=True, exist_ok=True)
        Image.fromarray(image).save(Path(SCREENSHOTS) / f"{name}.png")


@pytest.mark.slow
def test_browser_draws_every_mode(
    browser: DevTools, cube_page: Path, creased: g1patch.Surface, tmp_path: Path
) -> None:
    creased_page = write_view(tmp_path / "creased.html", creased.network)
    shots = {}
    for page in (cube_page, creased_page):
        for mode in MODES:
            image, covered = shoot(browser, page, mode)
            _keep(image, f"{page.stem}-{mode}")
            shots[page.stem, mode] = image, covered
            height, width = covered.shape
            fraction = covered.mean()
            assert 0.12 < fraction < 0.7, (
                page.name,
                mode,
                fraction,
            )  # the surface, framed: not blank, not all
            rows, columns = np.nonzero(covered)
            assert abs(rows.mean() / height - 0.5) < 0.1 and abs(columns.mean() / width - 0.5) < 0.1
            assert (
                np.ptp(rows) > 0.6 * height
            )  # framed to the silhouette: it fills most of the height
            surface = image[covered]
            assert surface.std(axis=0).max() > 10  # lit, not a flat silhouette
    for page in ("cube", "creased"):
        shaded, covered = shots[page, "shaded"]
        zebra, _ = shots[page, "zebra"]
        deviation, _ = shots[page, "deviation"]
        middle = range(int(0.35 * covered.shape[0]), int(0.65 * covered.shape[0]), 10)
        stripes = [_alternations(zebra[y], covered[y]) for y in middle]
        shaded_changes = [_alternations(shaded[y], covered[y]) for y in middle]
        assert np.median(stripes) >= 6, (page, stripes)  # stripes: many light/dark alternations
        assert np.median(shaded_changes) <= 3, (page, shaded_changes)  # shading varies slowly
        difference = np.abs(deviation.astype(int) - shaded.astype(int))[covered].max(axis=-1)
        assert (difference > 30).mean() > 0.5  # the deviation mode is a different picture

    # the creased cube's edges are coloured by their angle (plasma's yellow end), the exact one's
    # not
    def yellowish(image: np.ndarray, covered: np.ndarray) -> int:
        surface = image[covered].astype(int)
        return int(((surface[:, 0] > 200) & (surface[:, 1] > 120) & (surface[:, 2] < 110)).sum())

    assert (
        yellowish(*shots["creased", "deviation"]) > 500
        and yellowish(*shots["cube", "deviation"]) == 0
    )
    assert _errors(browser) == []
    assert _requests(browser) <= {"file", "data", "about"}, _requests(browser)


@pytest.mark.slow
def test_browser_draws_the_uv_checker_of_a_textured_cage(
    browser: DevTools, cube_page: Path, tmp_path: Path
) -> None:
    """A cage with ``vt`` (one chart per face, 8 × 8 checker squares a unit, a face a quarter
    unit: two squares a side): the ``uv`` mode draws the checker (light and dark alternate along
    a scanline, where shading varies slowly), no errors; a page without UVs offers no such mode."""
    square = [(0.0, 0.0), (0.25, 0.0), (0.25, 0.25), (0.0, 0.25)]
    lines = [f"v {x} {y} {z}" for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    lines += [f"vt {u} {v}" for u, v in square]
    faces = [(0, 4, 6, 2), (1, 3, 7, 5), (0, 1, 5, 4), (2, 6, 7, 3), (0, 2, 3, 1), (4, 5, 7, 6)]
    lines += ["f " + " ".join(f"{v + 1}/{k + 1}" for k, v in enumerate(face)) for face in faces]
    source = tmp_path / "textured.obj"
    source.write_text("\n".join(lines) + "\n")
    page = write_view(tmp_path / "textured.html", g1patch.smooth(source, method="gregory").network)
    shaded, covered = shoot(browser, page, "shaded")
    checker, _ = shoot(browser, page, "uv")
    _keep(checker, "textured-uv")
    middle = range(int(0.35 * covered.shape[0]), int(0.65 * covered.shape[0]), 10)
    assert np.median([_alternations(checker[y], covered[y]) for y in middle]) >= 4
    assert np.median([_alternations(shaded[y], covered[y]) for y in middle]) <= 3
    assert browser.evaluate("document.getElementById('uv-mode') !== null")
    shoot(browser, cube_page, "shaded")
    assert browser.evaluate("document.getElementById('uv-mode') === null")
    assert _errors(browser) == []


@pytest.mark.slow
def test_browser_draws_the_distance_to_a_scan(browser: DevTools, tmp_path: Path) -> None:
    """A surface viewed with the scan it was fitted to (here: a coarse triangulation of its own
    samples, so the distance varies over each triangle): the distance mode colours it, darkest
    at the scan's vertices, with its legend; no errors."""
    surface = g1patch.smooth(g1patch.shapes.cube_sphere(1), method="gregory")
    points, triangles = surface.tessellate(3)
    page = Path(surface.view(tmp_path / "distance.html", scan=(points, triangles)))
    shaded, covered = shoot(browser, page, "shaded")
    coloured, _ = shoot(browser, page, "distance")
    _keep(coloured, "distance")
    difference = np.abs(coloured.astype(int) - shaded.astype(int))[covered].max(axis=-1)
    assert (difference > 30).mean() > 0.5  # a different picture from the shading
    legend = "getComputedStyle(document.getElementById('distance-legend')).display"
    assert browser.evaluate(legend) == "block"
    assert _errors(browser) == []


def test_cli_view_help(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as done:
        main(["view", "--help"])
    assert done.value.code == 0
    text = capsys.readouterr().out
    assert (
        "examples:" in text
        and "g1patch view surface.npz -o surface.html" in text
        and "--force" in text
    )
