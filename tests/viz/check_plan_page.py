#!/usr/bin/python3
"""The 3D page in headless Chromium (ctest viz.plan_page_in_chromium).

    check_plan_page.py TIMEOPT_CLI SOURCE_DIR

Plans on the shipped forest with --html and --trajectory, writes `timeopt view` of the trajectory
file too, and for each page, in Debian's headless Chromium with software WebGL (SwiftShader) and
10 s of virtual time:
- the page becomes ready: <body data-ready="true">;
- data-samples equals the number of rows `timeopt export --format csv --rate 50` gives for the same
  trajectory (the page samples at 50 Hz);
- a screenshot is a real picture: its 3D half holds many colours, among them the path's (a red or
  orange tone) and the voxels' grey, not one background colour.
Chromium missing is a failure, not a skip (it is in scripts/install_deps.sh's test group).
"""

import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import zlib

CHROMIUM_FLAGS = ["--headless=new", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                  "--disable-gpu-sandbox", "--virtual-time-budget=10000", "--window-size=1400,900",
                  "--hide-scrollbars", "--no-first-run", "--disable-extensions"]


def png_pixels(path):
    """(width, height, rows of (r, g, b)) of an 8-bit RGB or RGBA PNG, by zlib and the PNG filters."""
    with open(path, "rb") as f:
        data = f.read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, width = 8, b"", 0
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour = struct.unpack(">IIBB", body[:10])
            assert depth == 8 and colour in (2, 6), "PNG depth %d colour type %d" % (depth, colour)
            channels = 3 if colour == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw = zlib.decompress(idat)
    stride = width * channels
    rows, previous = [], bytearray(stride)
    for y in range(height):
        line = raw[y * (stride + 1):(y + 1) * (stride + 1)]
        kind, row = line[0], bytearray(line[1:])
        for x in range(stride):
            a = row[x - channels] if x >= channels else 0
            b = previous[x]
            c = previous[x - channels] if x >= channels else 0
            if kind == 1:
                row[x] = (row[x] + a) & 255
            elif kind == 2:
                row[x] = (row[x] + b) & 255
            elif kind == 3:
                row[x] = (row[x] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                row[x] = (row[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append([tuple(row[i:i + 3]) for i in range(0, stride, channels)])
        previous = row
    return width, height, rows


def main(cli, source):
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        print("FAIL: no chromium on PATH (install Debian's chromium: scripts/install_deps.sh)")
        return 1
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        plan_page, view_page = os.path.join(tmp, "plan.html"), os.path.join(tmp, "view.html")
        traj = os.path.join(tmp, "t.json")
        subprocess.run([cli, "plan", "-q", "--html", plan_page, "--trajectory", traj, "-o", os.path.join(tmp, "p.csv")],
                       check=True, cwd=source)
        subprocess.run([cli, "view", traj, "--map", os.path.join(source, "maps", "forest_20x20.bt"), "-o", view_page,
                        "--max-velocity", "2", "--max-acceleration", "2", "--max-jerk", "10"], check=True)
        rows_csv = os.path.join(tmp, "s.csv")
        subprocess.run([cli, "export", traj, "--format", "csv", "--rate", "50", "-o", rows_csv], check=True)
        with open(rows_csv) as f:
            expected = sum(1 for _ in f) - 1
        for page in (plan_page, view_page):
            name = os.path.basename(page)
            size = os.path.getsize(page)
            if size > 15 << 20:
                failures.append("%s: %d bytes, above 15 MB" % (name, size))
            profile = os.path.join(tmp, "profile-" + name)
            dom = subprocess.run([chromium] + CHROMIUM_FLAGS + ["--user-data-dir=" + profile, "--dump-dom",
                                                               "file://" + page],
                                 capture_output=True, text=True, timeout=120).stdout
            body = re.search(r"<body[^>]*>", dom)
            body = body.group(0) if body else ""
            if 'data-ready="true"' not in body:
                failures.append("%s: not ready in 10 s of virtual time (%s)" % (name, body or "no <body>"))
            samples = re.search(r'data-samples="(\d+)"', body)
            if not samples or int(samples.group(1)) != expected:
                failures.append("%s: data-samples %s, the trajectory has %d samples at 50 Hz"
                                % (name, samples.group(1) if samples else "missing", expected))
            shot = os.path.join(tmp, name + ".png")
            subprocess.run([chromium] + CHROMIUM_FLAGS + ["--user-data-dir=" + profile, "--screenshot=" + shot,
                                                         "file://" + page], capture_output=True, timeout=120)
            if not os.path.exists(shot):
                failures.append("%s: no screenshot" % name)
                continue
            width, height, pixels = png_pixels(shot)
            colours, path_tones, greys = set(), 0, 0
            for y in range(0, height, 2):
                for x in range(0, int(width * 0.6), 2):
                    r, g, b = pixels[y][x]
                    colours.add((r, g, b))
                    path_tones += r > 180 and g < 170 and b < 90
                    greys += abs(r - g) < 12 and abs(g - b) < 14 and 90 < r < 200
            print("%s: %d bytes, body %s, 3D half: %d colours, %d path-tone and %d grey pixels (of every 4th)"
                  % (name, size, body, len(colours), path_tones, greys))
            # A page whose WebGL failed shows only its background (1 colour) and the colour bar's
            # box (a few hundred pixels of the gradient); the default plan's draws 1,252 colours,
            # about 190 path-tone and 9,800 grey pixels on this grid, so these floors leave a
            # factor of 5-20 for other machines' antialiasing and still catch an empty view.
            if len(colours) < 200 or path_tones < 20 or greys < 500:
                failures.append("%s: the screenshot's 3D half looks blank (%d colours, %d path, %d grey)"
                                % (name, len(colours), path_tones, greys))
    for message in failures:
        print("FAIL:", message)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
