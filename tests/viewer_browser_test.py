#!/usr/bin/python3
"""Browser test of the HTML pages of `dsreg view` and of the viewer library (CTest: viewer_browser).

Debian's Chromium opens each page from disk, headless, with WebGL on SwiftShader (the CPU), and
gives a screenshot, the DOM after the scripts ran (--dump-dom) and the console (--enable-logging).
Each page is opened through a copy that carries a Content-Security-Policy of the test's own
forbidding every load (files, network, anything), so that a page referring to anything outside
itself shows in the console; a control page with external references checks that it does.

Pages of `dsreg view` (goursat with its digital surface; two layers with names out of ASCII), of
`dsreg regularize --html` (a cube with Ambrosio-Tortorelli normals) and of the library
(viewer_test_pages: labelled spheres). Checked: the page reports itself ready with no error, the
console is empty, the mesh covers a good part of the picture with shading (many grey levels),
each colour mode / toggle / layer changes the picture, the AT feature map shows red feature lines,
a run's page holds its summary, a labelled sphere shows every label's colour (the legend's
colours, read from the DOM) on the front of its faces and the outside label on their back, and
file names out of ASCII give a working page.

Environment: DSREG (the dsreg executable), DSREG_TEST_PAGES (tests/viewer_test_pages). Needs
chromium and python3-pil (scripts/install-deps.sh --viewer). Run with Debian's /usr/bin/python3.
"""
import concurrent.futures
import os
import re
import shutil
import subprocess
import sys
import tempfile

from PIL import Image, ImageChops

DSREG = os.environ["DSREG"]
TEST_PAGES = os.environ["DSREG_TEST_PAGES"]
SIZE = (640, 480)
BACKGROUND = (0x1D, 0x21, 0x27)  # the page's clear colour (viewer.js)
STRICT_POLICY = ('<meta http-equiv="Content-Security-Policy" content="default-src \'none\'; '
                 'script-src \'unsafe-inline\'; style-src \'unsafe-inline\'">')

failures = []


def check(name, condition, detail=""):
    print(("ok   " if condition else "FAIL ") + name + (": " + detail if detail else ""))
    if not condition:
        failures.append(name)


class Shot:
    """One page opened by Chromium: its screenshot, <html> attributes, DOM text and console lines."""

    def __init__(self, image, dom, console):
        self.image = image.convert("RGB")
        self.dom = dom
        self.console = console
        match = re.search(r"<html[^>]*>", dom)
        self.attributes = dict(re.findall(r'([\w-]+)="([^"]*)"', match.group(0))) if match else {}

    def ready(self):
        return self.attributes.get("data-status") == "ready" and self.attributes.get("data-errors") == "0"


def open_page(page, fragment, work):
    """Opens a copy of `page` under the strict policy at #fragment (panels hidden unless asked)."""
    folder = tempfile.mkdtemp(dir=work)
    copy = os.path.join(folder, os.path.basename(page))
    with open(page, "rb") as source:
        html = source.read()
    with open(copy, "wb") as out:
        out.write(html.replace(b"<head>", b"<head>\n" + STRICT_POLICY.encode(), 1))
    png = os.path.join(folder, "shot.png")
    command = ["chromium", "--headless=new", "--no-sandbox", "--use-angle=swiftshader",
               "--enable-unsafe-swiftshader", "--no-first-run", "--disable-background-networking",
               "--disable-component-update", "--disable-sync", "--disable-quic", "--hide-scrollbars",
               "--user-data-dir=" + os.path.join(folder, "profile"), "--window-size=%d,%d" % SIZE,
               "--enable-logging=stderr", "--v=0", "--screenshot=" + png, "--dump-dom",
               "file://" + copy + "#" + fragment]
    run = subprocess.run(command, capture_output=True, timeout=120)
    console = [line for line in run.stderr.decode("utf-8", "replace").splitlines() if ":CONSOLE" in line]
    if not os.path.exists(png):
        raise RuntimeError("no screenshot of %s#%s: %s" % (page, fragment, run.stderr.decode()[-2000:]))
    return Shot(Image.open(png), run.stdout.decode("utf-8", "replace"), console)


def object_pixels(image):
    """Pixels that differ from the background by more than 12 in some channel."""
    return [p for p in image.getdata() if max(abs(a - b) for a, b in zip(p, BACKGROUND)) > 12]


def coverage(image):
    return len(object_pixels(image)) / (image.width * image.height)


def grey_levels(image):
    """Distinct luminance levels (bins of 4) holding at least 0.2% of the object's pixels."""
    pixels = object_pixels(image)
    counts = {}
    for r, g, b in pixels:
        level = int(0.299 * r + 0.587 * g + 0.114 * b) // 4
        counts[level] = counts.get(level, 0) + 1
    return sum(1 for n in counts.values() if n >= 0.002 * len(pixels))


def changed_share(a, b):
    """Share of the pixels whose colour differs by more than 24 in some channel."""
    difference = ImageChops.difference(a.image, b.image).getdata()
    return sum(1 for p in difference if max(p) > 24) / len(difference)


def hue_share(image, rgb, tolerance=12):
    """Share of the object's pixels (saturation > 0.25) whose hue is within `tolerance` degrees of rgb's."""
    target = Image.new("RGB", (1, 1), rgb).convert("HSV").getpixel((0, 0))[0] * 360 / 255
    hsv = Image.frombytes("RGB", image.size, image.tobytes()).convert("HSV").getdata()
    mask = [max(abs(a - b) for a, b in zip(p, BACKGROUND)) > 12 for p in image.getdata()]
    total = sum(mask)
    near = 0
    for (h, s, _), inside in zip(hsv, mask):
        if inside and s > 64 and min(abs(h * 360 / 255 - target), 360 - abs(h * 360 / 255 - target)) <= tolerance:
            near += 1
    return near / max(total, 1)


def legend_colours(dom):
    """{label: (r, g, b)} from the legend's swatches (the page's own palette)."""
    found = re.findall(r'background: rgb\((\d+), (\d+), (\d+)\);"></span> label (-?\d+)', dom)
    return {int(label): (int(r), int(g), int(b)) for r, g, b, label in found}


def dsreg(*arguments):
    subprocess.run([DSREG, *arguments, "-q"], check=True)


def main():
    work = tempfile.mkdtemp(prefix="dsreg_viewer_test_")
    try:
        run_checks(work)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print("%d failed" % len(failures))
    return 1 if failures else 0


def run_checks(work):
    path = lambda name: os.path.join(work, name)
    dsreg("regularize", "--shape", "goursat", "--h", "0.5", "-o", path("g.ply"), "--input-mesh", path("g-digital.ply"))
    cube = "(0.8*x+0.6*y)^16+(-0.48*x+0.64*y+0.6*z)^16+(0.36*x-0.48*y+0.8*z)^16-1"
    dsreg("regularize", "--shape", cube, "--box", "1.8", "--h", "0.1", "--radius", "0.3", "--normals", "at",
          "-o", path("cube.ply"), "--html", path("cube.html"))  # the page of a run
    dsreg("view", path("g.ply"), "--digital", path("g-digital.ply"), "-o", path("g.html"))
    # A digital surface with other faces (triangles) than its mesh: no per-face values on it.
    dsreg("regularize", "--shape", "goursat", "--h", "0.5", "--triangulate", "-o", path("gt.ply"),
          "--input-mesh", path("gt-digital.obj"))
    dsreg("view", path("g.ply"), "--digital", path("gt-digital.obj"), "-o", path("g-triangles.html"))
    names = ["géométrie 立方体.ply", "cube, copie №2.ply"]
    shutil.copy(path("g.ply"), path(names[0]))
    shutil.copy(path("cube.ply"), path(names[1]))
    layered = path("vue d'ensemble é.html")
    dsreg("view", path(names[0]), path(names[1]), "-o", layered)
    subprocess.run([TEST_PAGES, work], check=True)
    control = path("control.html")
    with open(control, "w") as out:
        out.write('<!DOCTYPE html><html><head></head><body><img src="https://example.invalid/a.png">'
                  '<script src="http://example.invalid/b.js"></script>'
                  '<script>fetch("https://example.invalid/c").catch(function () {});</script></body></html>')

    fixed = "panels=0&azimuth=30&elevation=20"
    jobs = {
        "plain": (path("g.html"), fixed),
        "deviation": (path("g.html"), fixed + "&colour=deviation"),
        "displacement": (path("g.html"), fixed + "&colour=displacement"),
        "wireframe": (path("g.html"), fixed + "&wireframe=1"),
        "digital": (path("g.html"), fixed + "&surface=0&digital=1"),
        "digital triangles": (path("g-triangles.html"), fixed + "&colour=deviation&digital=1&wireframe=1"),
        "cube plain": (path("cube.html"), fixed + "&features=0"),
        "cube features": (path("cube.html"), fixed + "&colour=features"),
        "labels": (path("labels.html"), "panels=0&azimuth=0&elevation=0&colour=labels"),
        "labels back": (path("labels-open.html"), "panels=0&azimuth=0&elevation=0&colour=labels"),
        "layer 1": (layered, fixed + "&layer=1"),
        "layer 2": (layered, fixed + "&layer=2"),
        "control": (control, ""),
    }
    with concurrent.futures.ThreadPoolExecutor(max_workers=2) as pool:
        futures = {name: pool.submit(open_page, page, fragment, work) for name, (page, fragment) in jobs.items()}
        shots = {name: future.result() for name, future in futures.items()}

    # Every page of dsreg: ready, no error, nothing in the console (no blocked load either).
    for name, shot in shots.items():
        if name == "control":
            continue
        check(name + ": ready, no error", shot.ready(), str(shot.attributes))
        check(name + ": console empty", not shot.console, "; ".join(shot.console)[:600])
    blocked = [line for line in shots["control"].console if "violates" in line or "Refused" in line]
    check("control page: its three external references are reported", len(blocked) >= 3, "; ".join(blocked)[:600])

    plain = shots["plain"]
    check("mesh covers the picture", coverage(plain.image) > 0.15, "%.3f" % coverage(plain.image))
    check("mesh is shaded", grey_levels(plain.image) >= 12, "%d levels" % grey_levels(plain.image))
    check("colour mode recorded", shots["deviation"].attributes.get("data-colour") == "deviation")
    for a, b in [("plain", "deviation"), ("plain", "displacement"), ("deviation", "displacement"),
                 ("plain", "wireframe"), ("plain", "digital"), ("cube plain", "cube features")]:
        share = changed_share(shots[a], shots[b])
        check("%s and %s differ" % (a, b), share > 0.05, "%.3f of the pixels" % share)
    check("digital surface alone is shaded", grey_levels(shots["digital"].image) >= 6)

    red = (190, 22, 30)  # the colour of v = 0 (viewer.js)
    features, smooth = hue_share(shots["cube features"].image, red), hue_share(shots["cube plain"].image, red)
    check("feature map shows red features", features > 0.01 and smooth < 0.002, "%.4f vs %.4f" % (features, smooth))
    summary = re.findall(r"<tr><th>([^<]*)</th><td>([^<]*)</td></tr>", shots["cube features"].dom)
    check("run page: summary of the run", {"input", "surfels", "normal field", "regularize", "total"}
          <= {name for name, _ in summary}, str(summary)[:400])

    colours = legend_colours(shots["labels"].dom)
    check("legend lists labels 0-4", sorted(colours) == [0, 1, 2, 3, 4], str(colours))
    for label in (1, 2, 3, 4):
        share = hue_share(shots["labels"].image, colours.get(label, (0, 0, 0)))
        check("label %d shows (front of its faces)" % label, share > 0.1, "%.3f of the sphere" % share)
    back = legend_colours(shots["labels back"].dom)
    share = hue_share(shots["labels back"].image, back.get(5, (0, 0, 0)))
    check("outside label shows on the back of the faces", share > 0.5, "%.3f of the bowl" % share)
    for label in (1, 2, 3, 4):
        share = hue_share(shots["labels back"].image, back.get(label, (0, 0, 0)))
        check("inside label %d hidden behind the bowl" % label, share < 0.05, "%.3f" % share)

    check("layers switch", shots["layer 2"].attributes.get("data-layer") == "2" and
          changed_share(shots["layer 1"], shots["layer 2"]) > 0.05)
    for number, name in enumerate(names, 1):
        shown = re.findall(r"<h2>([^<]*)</h2>", shots["layer %d" % number].dom)
        check("layer %d is %s (a name out of ASCII)" % (number, name), shown == [name], str(shown))


if __name__ == "__main__":
    sys.exit(main())
