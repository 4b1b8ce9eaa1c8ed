"""Image metrics of the core against scikit-image on the same display luma (runtime: < 1 s)."""
import numpy as np
import pytest
from skimage.metrics import peak_signal_noise_ratio, structural_similarity

import photonsplat as ps


def display_luma(image):
    """linear -> clamp [0, 1] -> sRGB, then Rec. 709 weights on the encoded values (metrics.h)."""
    c = np.clip(np.asarray(image, np.float64)[..., :3], 0.0, 1.0)
    encoded = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)
    return encoded @ np.array([0.2126, 0.7152, 0.0722])


def image_pair(seed, shape=(40, 56), channels=3):
    """A smooth 'render' with values above 1 and below 0.003 (both ends of the display curve), and a noisy copy."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:shape[0], 0:shape[1]]
    base = 0.6 + 0.5 * np.sin(x / 7.0)[..., None] * np.cos(y / 5.0)[..., None] * np.array([1.0, 0.7, 0.4])
    base[:5, :8] = 0.001
    reference = np.concatenate([base, np.ones(shape + (1,))], axis=2)[..., :channels].astype(np.float32)
    image = reference.copy()
    image[..., :3] += rng.normal(0.0, 0.08, shape + (3,)).astype(np.float32)
    return image, reference


def skimage_ssim(image, reference):
    return structural_similarity(display_luma(image), display_luma(reference), gaussian_weights=True, sigma=1.5,
                                 use_sample_covariance=False, data_range=1.0)


@pytest.mark.parametrize("seed,channels", [(0, 3), (1, 4), (2, 3)])
def test_ssim_and_psnr_agree_with_scikit_image(seed, channels):
    image, reference = image_pair(seed, channels=channels)
    ours_ssim, ours_psnr = ps.ssim(image, reference), ps.psnr(image, reference)
    theirs_ssim = skimage_ssim(image, reference)
    theirs_psnr = peak_signal_noise_ratio(display_luma(reference), display_luma(image), data_range=1.0)
    assert 0.2 < theirs_ssim < 0.95                     # a pair the metric can tell apart from identity
    assert abs(ours_ssim - theirs_ssim) < 1e-3
    assert abs(ours_psnr - theirs_psnr) < 1e-3


def test_ssim_on_a_rendered_image_against_a_blurred_one():
    """Structure, not only noise: a render against a shifted, blurred copy of itself."""
    import scenes
    camera = ps.look_at_camera(eye=(0, -3.9, 1), target=(0, 0, 1), width=48, height=40)
    image, _ = ps.render(scenes.cornell_box(), camera, ps.RenderSettings(photons=20000))
    blurred = (np.roll(image, 1, axis=1) + image + np.roll(image, 1, axis=0)) / 3.0
    assert abs(ps.ssim(image, blurred) - skimage_ssim(image, blurred)) < 1e-3
    assert abs(ps.psnr(image, blurred) - peak_signal_noise_ratio(display_luma(blurred), display_luma(image),
                                                                 data_range=1.0)) < 1e-3


def test_linear_metrics():
    image, reference = image_pair(3)
    d = image[..., :3].astype(np.float64) - reference[..., :3]
    assert ps.rmse(image, reference) == pytest.approx(np.sqrt(np.mean(d * d)), rel=1e-6)
    expected = np.mean(d * d / (reference[..., :3].astype(np.float64) ** 2 + ps.RELMSE_EPSILON))
    assert ps.relmse(image, reference) == pytest.approx(expected, rel=1e-6)
    assert ps.RELMSE_EPSILON == 0.01


def test_identical_images():
    _, reference = image_pair(4)
    assert ps.ssim(reference, reference) == pytest.approx(1.0, abs=1e-12)
    assert ps.psnr(reference, reference) == float("inf")      # as scikit-image; documented in metrics.h
    assert ps.rmse(reference, reference) == 0.0 and ps.relmse(reference, reference) == 0.0


def test_alpha_is_ignored():
    image, reference = image_pair(5, channels=4)
    other = image.copy()
    other[..., 3] = 0.25
    assert ps.ssim(other, reference) == ps.ssim(image, reference)
    assert ps.ssim(image[..., :3], reference) == ps.ssim(image, reference)


@pytest.mark.parametrize("metric", [ps.psnr, ps.ssim, ps.rmse, ps.relmse])
def test_bad_input_names_the_field(metric):
    image, reference = image_pair(6)
    with pytest.raises(ValueError, match="reference"):
        metric(image, reference[:-1])
    with pytest.raises(ValueError, match="image"):
        metric(image[..., :2], reference)
    with pytest.raises(ValueError, match="reference"):
        metric(image, reference[0])
    bad = reference.copy()
    bad[3, 4, 1] = np.nan
    with pytest.raises(ValueError, match="reference.*NaN"):
        metric(image, bad)
    with pytest.raises(ValueError, match="image"):
        metric(np.array([["a"]]), reference)


def test_ssim_needs_its_window():
    image, reference = image_pair(7, shape=(10, 30))
    with pytest.raises(ValueError, match="11"):
        ps.ssim(image, reference)
    assert np.isfinite(ps.psnr(image, reference))             # the other metrics work at any size
