#!/usr/bin/env python3
"""Tests of the host's board-vm checks (verify.py) on pictures made here:
the checks must pass what the kiosk shows and fail what it must not.
Run by ctest (BoardVm.VerifyChecks); standard library only."""

import os
import struct
import subprocess
import sys
import tempfile
import unittest
import zlib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import verify  # noqa: E402

WIDTH, HEIGHT = 160, 120


def colour_bars(width=WIDTH, height=HEIGHT):
    """vimc's kind of test pattern: vertical bars of 8 colours."""
    bars = [(255, 255, 255), (255, 255, 0), (0, 255, 255), (0, 255, 0), (255, 0, 255), (255, 0, 0), (0, 0, 255),
            (40, 40, 40)]
    rgb = bytearray()
    for _ in range(height):
        for x in range(width):
            rgb += bytes(bars[x * len(bars) // width])
    return [width, height, rgb]


def with_status_bar(image, bar_rows=12, text_pixels=60):
    """What StatusOverlay draws: black at alpha 160/255 over the bottom rows,
    and white text in them."""
    width, height, rgb = image
    keep = 1.0 - 160.0 / 255.0
    for y in range(height - bar_rows, height):
        for i in range(y * width * 3, (y + 1) * width * 3):
            rgb[i] = int(rgb[i] * keep + 0.5)
    for n in range(text_pixels):
        y, x = height - 10 + n % 6, 8 + n  # as cv::putText's glyphs, above the bar's bottom margin
        rgb[(y * width + x) * 3:(y * width + x) * 3 + 3] = b"\xff\xff\xff"
    return image


def frozen(image):
    return image[0], image[1], bytes(image[2])


def write_png(path, image, filter_of_row):
    """An RGB PNG whose rows use the given filter types (0-4)."""
    width, height, rgb = image
    stride = width * 3
    raw, previous = bytearray(), bytes(stride)
    for y in range(height):
        row = rgb[y * stride:(y + 1) * stride]
        kind = filter_of_row(y)
        out = bytearray()
        for x in range(stride):
            left = row[x - 3] if x >= 3 else 0
            up = previous[x]
            up_left = previous[x - 3] if x >= 3 else 0
            if kind == 0:
                predictor = 0
            elif kind == 1:
                predictor = left
            elif kind == 2:
                predictor = up
            elif kind == 3:
                predictor = (left + up) >> 1
            else:
                p = left + up - up_left
                pa, pb, pc = abs(p - left), abs(p - up), abs(p - up_left)
                predictor = left if pa <= pb and pa <= pc else (up if pb <= pc else up_left)
            out.append((row[x] - predictor) & 0xFF)
        raw += bytes([kind]) + out
        previous = row

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(bytes(raw))) + chunk(b"IEND", b""))


class ScreenChecks(unittest.TestCase):
    def test_the_camera_picture_with_its_status_bar_passes(self):
        passed, detail = verify.camera_picture_with_status_bar(frozen(with_status_bar(colour_bars())))
        self.assertTrue(passed, detail)

    def test_a_picture_without_the_bar_a_bar_without_text_and_black_fail(self):
        for name, image in (("no bar", colour_bars()), ("no text", with_status_bar(colour_bars(), text_pixels=0)),
                            ("black", [WIDTH, HEIGHT, bytearray(WIDTH * HEIGHT * 3)])):
            passed, detail = verify.camera_picture_with_status_bar(frozen(image))
            self.assertFalse(passed, f"{name}: {detail}")

    def test_a_letterboxed_screen_is_checked_on_its_picture(self):
        picture = with_status_bar(colour_bars())
        black = bytes(WIDTH * 3 * 20)
        screen = (WIDTH, HEIGHT + 40, black + bytes(picture[2]) + black)
        passed, detail = verify.camera_picture_with_status_bar(screen)
        self.assertTrue(passed, detail)
        passed, detail = verify.images_match(screen, frozen(picture), 0.0, 0)
        self.assertTrue(passed, detail)

    def test_images_match_within_the_limits_and_not_beyond(self):
        reference = frozen(colour_bars())
        noisy = bytearray(reference[2])
        for i in range(0, len(noisy), 2):
            noisy[i] ^= 1  # half the codes off by one: mean 0.5
        self.assertTrue(verify.images_match((WIDTH, HEIGHT, bytes(noisy)), reference, 0.6, 1)[0])
        self.assertFalse(verify.images_match((WIDTH, HEIGHT, bytes(noisy)), reference, 0.4, 1)[0])
        # A frame shown one pixel to the right: the bars' edges differ.
        shifted = bytearray(reference[2])
        for y in range(HEIGHT):
            row = slice(y * WIDTH * 3, (y + 1) * WIDTH * 3)
            shifted[row] = b"\0\0\0" + bytes(reference[2][row])[:-3]
        passed, detail = verify.images_match((WIDTH, HEIGHT, bytes(shifted)), reference, 1.0, 4)
        self.assertFalse(passed, detail)
        passed, detail = verify.images_match((WIDTH, HEIGHT // 2, reference[2][:WIDTH * HEIGHT * 3 // 2]), reference,
                                             1.0, 4)
        self.assertFalse(passed, detail)


@unittest.skipUnless(os.environ.get("PROBELIGHT_BINARY"), "PROBELIGHT_BINARY not set (ctest sets it)")
class WhatTheKioskDraws(unittest.TestCase):
    """The screen check on the kiosk's own frame: colour bars with no tag
    (as vimc's test pattern), replayed through `probelight run`, come out
    with the status bar that the check must find; the bars alone must not
    pass. The frame is a PNG of the kiosk's PNG writer, so read_png is tried
    on it too."""

    def test_the_kiosk_frame_of_a_test_pattern_passes_and_the_pattern_alone_does_not(self):
        repository = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
        with tempfile.TemporaryDirectory() as folder:
            bars = os.path.join(folder, "bars.png")
            write_png(bars, frozen(colour_bars(640, 480)), lambda y: 0)
            out = os.path.join(folder, "out")
            run = subprocess.run([os.environ["PROBELIGHT_BINARY"], "run", "--source", "images", "--images", bars,
                                  "--calibration", os.path.join(repository, "board", "camera.yaml"),
                                  "--rig", os.path.join(repository, "board", "rig.yaml"), "--display", "headless",
                                  "--frames", "1", "--save-every", "1", "--out", out],
                                 capture_output=True, text=True, timeout=120)
            self.assertEqual(run.returncode, 0, run.stderr)
            frame = verify.read_png(os.path.join(out, "frame_000000.png"))
            passed, detail = verify.camera_picture_with_status_bar(frame)
            self.assertTrue(passed, detail)
            passed, detail = verify.camera_picture_with_status_bar(verify.read_png(bars))
            self.assertFalse(passed, detail)


class PngReading(unittest.TestCase):
    def test_every_filter_type_decodes_to_the_same_pixels(self):
        image = frozen(with_status_bar(colour_bars()))
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, "frame.png")
            write_png(path, image, lambda y: y % 5)
            self.assertEqual(verify.read_png(path), image)

    def test_not_a_png_is_an_error_naming_the_file(self):
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, "frame.png")
            with open(path, "wb") as f:
                f.write(b"P6\n1 1\n255\n\0\0\0")
            with self.assertRaisesRegex(ValueError, "frame.png: not a PNG"):
                verify.read_png(path)


class CameraReport(unittest.TestCase):
    STAGE = {"median_ms": 2.0, "p95_ms": 3.0, "runs": 12, "skipped": 0}

    def report(self, **changes):
        report = {"frames": 12, "camera": {"stream": "BGR888 640x480 (stride 1920)", "frame_upload": "packed rgb upload"},
                  "stages": {name: dict(self.STAGE) for name in ("upload", "detect_pose", "render", "present")}}
        report["stages"]["probe_to_cube"] = {"runs": 0, "skipped": 12, "skip_reasons": {"no tag": 12}}
        # As report.json writes a stage that only skipped: its timings null.
        report["stages"]["match_noise"] = {"median_ms": None, "p95_ms": None, "runs": 0, "skipped": 12,
                                           "skip_reasons": {"off": 12}}
        report.update(changes)
        return report

    def test_frames_a_stream_and_the_per_frame_stages_pass(self):
        passed, detail = verify.camera_run_report(self.report(), 10)
        self.assertTrue(passed, detail)
        self.assertIn("probe_to_cube 0 runs/12 skips", detail)
        self.assertIn("match_noise 0 runs/12 skips no timing", detail)

    def test_too_few_frames_no_stream_or_an_untimed_stage_fail(self):
        self.assertFalse(verify.camera_run_report(self.report(frames=3), 10)[0])
        self.assertFalse(verify.camera_run_report(self.report(camera={"stream": ""}), 10)[0])
        untimed = self.report()
        del untimed["stages"]["render"]["median_ms"]
        self.assertFalse(verify.camera_run_report(untimed, 10)[0])


class CameraZeroCopy(unittest.TestCase):
    def report(self, **camera):
        section = {"frames_by_upload_path": {"dmabuf import": 10}, "frames_in_dmabufs": 10,
                   "dmabuf_import_fallbacks": 0, "dmabuf_import_vs_upload_mean_codes": 0.0}
        section.update(camera)
        return {"frames": 10, "camera": section}

    def uploaded(self, **camera):
        report = self.report(frames_by_upload_path={"packed rgb upload": 10}, **camera)
        del report["camera"]["dmabuf_import_vs_upload_mean_codes"]
        return report

    def test_every_frame_imported_and_matching_the_upload_passes(self):
        passed, detail = verify.camera_zero_copy(self.report(), 10)
        self.assertTrue(passed, detail)
        self.assertIn("imported (either required); by path: 10 dmabuf import", detail)

    def test_a_mismatch_an_uncompared_import_or_no_dmabufs_fail(self):
        self.assertFalse(verify.camera_zero_copy(self.report(dmabuf_import_vs_upload_mean_codes=3.5), 10)[0])
        uncompared = self.report()
        del uncompared["camera"]["dmabuf_import_vs_upload_mean_codes"]
        self.assertFalse(verify.camera_zero_copy(uncompared, 10)[0])
        self.assertFalse(verify.camera_zero_copy(self.report(frames_in_dmabufs=0), 10)[0])

    def test_the_upload_path_passes_with_its_cause_only(self):
        self.assertFalse(verify.camera_zero_copy(self.uploaded(), 10)[0])
        passed, detail = verify.camera_zero_copy(
            self.uploaded(dmabuf_import_fallbacks=1, dmabuf_import_problem="BGR888 636x480: EGL_BAD_ALLOC"), 10)
        self.assertTrue(passed, detail)
        self.assertIn("uploaded (either required); by path: 10 packed rgb upload", detail)
        self.assertIn("why not imported: BGR888 636x480: EGL_BAD_ALLOC", detail)

    def test_a_guest_that_must_import_fails_on_the_upload_path(self):
        with_a_cause = self.uploaded(dmabuf_import_fallbacks=1, dmabuf_import_problem="BGR888 636x480: EGL_BAD_ALLOC")
        passed, detail = verify.camera_zero_copy(with_a_cause, 10, "imported")
        self.assertFalse(passed, detail)
        self.assertIn("uploaded (imported required)", detail)
        self.assertTrue(verify.camera_zero_copy(self.report(), 10, "imported")[0])
        with self.assertRaises(ValueError):
            verify.camera_zero_copy(self.report(), 10, "uploaded")

    def test_frames_split_between_the_paths_fail(self):
        split = self.report(frames_by_upload_path={"dmabuf import": 4, "packed rgb upload": 6},
                            dmabuf_import_fallbacks=1, dmabuf_import_problem="a cause")
        self.assertFalse(verify.camera_zero_copy(split, 10)[0])


if __name__ == "__main__":
    unittest.main()
