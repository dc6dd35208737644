"""Image comparison: forgives one-pixel edge shifts, never a wrong colour, NaN or a wrong size."""
from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from cs451.compare import ImageTolerance, compare_images

from conftest import assert_images_match


def disk(shift=0, colour=(0.3, 0.9, 0.5), size=64):
    y, x = np.mgrid[:size, :size]
    img = np.zeros((size, size, 3))
    img[(x - 32 - shift) ** 2 + (y - 32) ** 2 < 20 ** 2] = colour
    return img


def test01_identical_images_pass():
    r = compare_images(disk(), disk())
    assert r.passed and r.max_error == 0


def test02_one_pixel_shift_is_forgiven_but_not_without_the_allowance():
    assert compare_images(disk(), disk(shift=1)).passed
    assert not compare_images(disk(), disk(shift=1), ImageTolerance(shift=0, max_bad_fraction=0.001)).passed
    assert not compare_images(disk(), disk(shift=3)).passed


def test03_wrong_colour_fails():
    r = compare_images(disk(), disk(colour=(0.3, 0.9, 0.55)))
    assert not r.passed and "differ by more than 0.016" in r.message


def test04_small_noise_under_threshold_passes():
    rng = np.random.default_rng(12345)
    assert compare_images(disk(), disk() + rng.uniform(-0.01, 0.01, (64, 64, 3))).passed


def test05_nan_and_shape_fail_with_a_reason():
    bad = disk()
    bad[10, 10, 0] = np.nan
    assert "NaN" in compare_images(disk(), bad).message
    r = compare_images(disk(), np.zeros((32, 64, 3)))
    assert not r.passed and "shape" in r.message


def test_a_failing_image_test_points_at_a_picture_of_where_it_differs(tmp_path, monkeypatch):
    monkeypatch.setenv("CS451_TEST_PICTURES", str(tmp_path))
    target = np.zeros((40, 60, 3))
    assert assert_images_match(target, target.copy(), ImageTolerance(), "same").passed
    assert not list(tmp_path.iterdir()), "a passing comparison writes nothing"
    mine = target.copy()
    mine[10:20, 10:30] = 0.5
    with pytest.raises(AssertionError, match="difference picture: .*a-wrong-patch.png") as err:
        assert_images_match(target, mine, ImageTolerance(), "a wrong patch")
    picture = np.asarray(Image.open(tmp_path / "a-wrong-patch.png"))
    assert picture.shape[1] > 4 * 60, str(err.value)            # four panels side by side
    third = picture[:, 2 * 64 + 20:2 * 64 + 40]                  # the grader's error map is red where it differs
    assert (third[..., 0] > 200).any() and str(tmp_path) in str(err.value)
