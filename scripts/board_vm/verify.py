"""The host's checks of what a board-vm guest left: screendumps against what
should be on the screen, and run reports. Pure functions of images and
JSON, standard library only, so that they can be tried on their own
(scripts/board_vm/verify_test.py).

An image here is (width, height, rgb bytes), 8-bit RGB, rows top first.
Each check returns (passed, detail): detail says what was measured against
what limit, for the report.
"""

import json
import os
import sys

# The PNG reader the benchmark's replay uses (standard library only).
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from png_to_ppm import read_png  # noqa: E402,F401  (verify.read_png for the callers)


def luma(r, g, b):
    # Rec601 weights: the status bar darkens all three channels alike, and
    # the test pattern's colour bars differ mostly in hue.
    return 0.299 * r + 0.587 * g + 0.114 * b


def row_luma(image, y):
    width, _, rgb = image
    row = rgb[y * width * 3:(y + 1) * width * 3]
    return sum(luma(row[i], row[i + 1], row[i + 2]) for i in range(0, len(row), 3)) / width


def row_median_luma(image, y):
    """A row's median: text over a bar moves it little, unlike the mean."""
    width, _, rgb = image
    row = rgb[y * width * 3:(y + 1) * width * 3]
    values = sorted(luma(row[i], row[i + 1], row[i + 2]) for i in range(0, len(row), 3))
    return values[len(values) // 2]


def picture_rows(image, black=4.0):
    """(top, bottom) rows of what is shown, without black letterbox rows."""
    _, height, _ = image
    top, bottom = 0, height
    while top < bottom and row_luma(image, top) < black:
        top += 1
    while bottom > top and row_luma(image, bottom - 1) < black:
        bottom -= 1
    return top, bottom


def camera_picture_with_status_bar(image):
    """The kiosk's frame from a camera with its status bar: a picture (not
    black, many colours) whose bottom rows are darkened and carry white
    text, as ComposeStage's StatusOverlay draws it (black at alpha 160/255
    over the frame, 37% of its light; anti-aliased white text; at least 8
    rows high)."""
    width, height, rgb = image
    top, bottom = picture_rows(image)
    rows = bottom - top
    if rows < 64:
        return False, f"{rows} rows of picture on a {width}x{height} screen: black"
    mean = sum(row_luma(image, y) for y in range(top, bottom)) / rows
    colours = len({bytes(rgb[i:i + 3]) for i in range(top * width * 3, bottom * width * 3, 3 * 7)})
    # The picture's own light above where any bar reaches (the bar is 6% of
    # a 640x480 frame's height, 10% of a 320x240 one's), then the bar: the
    # bottom rows below 60% of it.
    step = max(4, rows // 16)
    reference = sum(row_median_luma(image, y) for y in range(bottom - 4 * step, bottom - 3 * step)) / step
    bar_top = bottom
    while bar_top > bottom - 3 * step and row_median_luma(image, bar_top - 1) <= 0.6 * reference:
        bar_top -= 1
    bar_rows = bottom - bar_top
    text_pixels = 0
    for y in range(bar_top, bottom):
        row = rgb[y * width * 3:(y + 1) * width * 3]
        # Anything this light in all three channels is text: the bar keeps
        # at most 37% of 255 (94).
        text_pixels += sum(1 for i in range(0, len(row), 3) if min(row[i], row[i + 1], row[i + 2]) >= 160)
    bar_luma = sum(row_median_luma(image, y) for y in range(bar_top, bottom)) / bar_rows if bar_rows else reference
    detail = (f"{width}x{height}, picture rows {top}-{bottom}, mean luma {mean:.0f}, {colours} colours; "
              f"status bar {bar_rows} rows (>= 8) at {bar_luma / max(reference, 1e-9):.2f} of the picture above, "
              f"{text_pixels} white text pixels in it (>= 20)")
    passed = mean >= 16 and colours >= 8 and bar_rows >= 8 and text_pixels >= 20
    return passed, detail


def images_match(screen, reference, mean_limit, p99_limit, letterboxed=True):
    """The screen shows the reference frame: the same size once black
    letterbox rows are cut from the screen (letterboxed), then mean and 99th
    percentile of |difference| over channels, in 8-bit codes."""
    sw, sh, srgb = screen
    rw, rh, rrgb = reference
    top, bottom = picture_rows(screen) if letterboxed else (0, sh)
    if sw != rw or bottom - top != rh:
        return False, f"screen picture {sw}x{bottom - top} (rows {top}-{bottom} of {sh}) is not the frame's {rw}x{rh}"
    offset = top * sw * 3
    histogram = [0] * 256
    total = 0
    for i in range(rw * rh * 3):
        d = abs(srgb[offset + i] - rrgb[i])
        histogram[d] += 1
        total += d
    count = rw * rh * 3
    mean = total / count
    running, p99 = 0, 255
    for value, n in enumerate(histogram):
        running += n
        if running >= 0.99 * count:
            p99 = value
            break
    maximum = max(v for v, n in enumerate(histogram) if n)
    passed = mean <= mean_limit and p99 <= p99_limit
    return passed, (f"{rw}x{rh}: mean |difference| {mean:.2f} codes (<= {mean_limit}), "
                    f"99th percentile {p99} (<= {p99_limit}), max {maximum}")


def camera_run_report(report, min_frames):
    """A run on the real camera: frames came, the negotiated stream is named,
    and the stages every frame goes through (upload, detect_pose, render,
    present) ran on each with a timing; the others' runs and skips listed."""
    frames = report.get("frames", 0)
    camera = report.get("camera", {})
    stream = camera.get("stream", "")
    stages = report.get("stages", {})
    every_frame = ("upload", "detect_pose", "render", "present")
    missing = [name for name in every_frame
               if stages.get(name, {}).get("runs", 0) < min_frames or "median_ms" not in stages.get(name, {})]
    timings = []
    for name, stage in sorted(stages.items()):
        runs, skipped = stage.get("runs", 0), stage.get("skipped", 0)
        # A stage that only skipped has median_ms null.
        timing = f"{stage['median_ms']:.1f} ms median" if stage.get("median_ms") is not None else "no timing"
        timings.append(f"{name} {runs} runs/{skipped} skips {timing}")
    passed = frames >= min_frames and bool(stream) and not missing
    return passed, (f"{frames} frames (>= {min_frames}), stream \"{stream}\", {camera.get('frame_upload', '?')}"
                    + (f"; stages without a run a frame: {', '.join(missing)}" if missing else "")
                    + f"; stages: {'; '.join(timings) or 'none'}")


def camera_zero_copy(report, min_frames, required="either"):
    """The camera's frames came in dmabufs and took one path through the
    GPU, as the product promises: either every frame was imported, none fell
    back, and the first imported frame matched the upload path within 3
    codes on average (the product's own tolerance); or none was imported,
    at most one import was given up, and the report names the cause.
    required="imported" accepts the first only (a guest whose driver is
    known to import the camera's buffers)."""
    if required not in ("either", "imported"):
        raise ValueError(f"camera-zero-copy: required path {required!r}: either or imported")
    camera = report.get("camera", {})
    by_path = camera.get("frames_by_upload_path", {})
    imported = by_path.get("dmabuf import", 0)
    in_dmabufs = camera.get("frames_in_dmabufs", 0)
    fallbacks = camera.get("dmabuf_import_fallbacks", 0)
    difference = camera.get("dmabuf_import_vs_upload_mean_codes")
    problem = camera.get("dmabuf_import_problem", "")
    all_imported = imported == in_dmabufs and fallbacks == 0 and difference is not None and difference <= 3.0
    all_uploaded_with_a_cause = imported == 0 and fallbacks <= 1 and bool(problem)
    passed = in_dmabufs >= min_frames and (all_imported or (required == "either" and all_uploaded_with_a_cause))
    taken = "imported" if all_imported else "uploaded" if all_uploaded_with_a_cause else "neither"
    paths = ", ".join(f"{count} {name}" for name, count in sorted(by_path.items()))
    compared = f"{difference:.2f} codes" if difference is not None else "not compared"
    return passed, (f"{in_dmabufs} frames in dmabufs (>= {min_frames}), {taken} ({required} required); "
                    f"by path: {paths or 'none'}; "
                    f"first import against the upload: {compared}; fallbacks {fallbacks}"
                    + (f"; why not imported: {problem}" if problem else ""))


def load_json(path):
    with open(path) as f:
        return json.load(f)
