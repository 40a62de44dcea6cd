import numpy as np
import pytest

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.registration.features import BLANK_GRADIENT_RMS, gradient_rms, orientation_field, to_grey


def test_to_grey_ranges():
    rgb = np.full((8, 9, 3), 255, np.uint8)
    assert to_grey(rgb).shape == (8, 9) and to_grey(rgb).max() == pytest.approx(1.0, abs=1e-5)
    raw = np.linspace(1000, 3000, 64, dtype=np.uint16).reshape(8, 8)  # 16-bit thermal: its used range is stretched
    g = to_grey(raw)
    assert g.min() == pytest.approx(0.0, abs=0.01) and g.max() == pytest.approx(1.0, abs=0.01)
    with pytest.raises(InputError, match="expected a 2-D grey"):
        to_grey(np.zeros((4, 4, 2)))


def test_orientation_field_ignores_contrast_reversal_and_gain(pair):
    visible = to_grey(pair[0])
    a = orientation_field(visible)
    b = orientation_field(1.0 - 0.3 * visible)  # inverted and with a quarter of the contrast
    assert a.shape == visible.shape + (2,)
    assert np.abs(a - b).max() < 1e-4


def test_blank_frames_have_no_gradient(pair):
    assert gradient_rms(np.full((50, 60), 0.4, np.float32)) < BLANK_GRADIENT_RMS
    assert gradient_rms(to_grey(pair[0])) > 10 * BLANK_GRADIENT_RMS


def test_coarse_search_turns_warped_fields_like_warped_images(pair):
    """The coarse search turns the RGB orientation field once per angle instead of recomputing it; turning an image
    by +angle turns its doubled-angle field by +2 angle, which must match the field of the turned image."""
    import cv2

    from rgbt_toolkit.registration.transforms import similarity

    grey = to_grey(pair[0])
    h, w = grey.shape
    inner = np.s_[20:-20, 20:-20]
    for angle in np.deg2rad([-5.0, 5.0]):
        m = similarity(1.0, angle, ((w - 1) / 2, (h - 1) / 2), ((w - 1) / 2, (h - 1) / 2))[:2]
        direct = orientation_field(cv2.warpAffine(grey, m, (w, h), flags=cv2.INTER_LINEAR))
        warped = cv2.warpAffine(orientation_field(grey), m, (w, h), flags=cv2.INTER_LINEAR)
        direct = (direct[..., 0] + 1j * direct[..., 1])[inner]
        turned = ((warped[..., 0] + 1j * warped[..., 1]) * np.exp(2j * angle))[inner]
        wrong = ((warped[..., 0] + 1j * warped[..., 1]) * np.exp(-2j * angle))[inner]

        def corr(a, b):
            return float(np.real(np.vdot(a, b)) / (np.linalg.norm(a) * np.linalg.norm(b)))

        assert corr(direct, turned) > 0.95
        assert corr(direct, turned) > corr(direct, wrong) + 0.02


def test_coarse_search_finds_a_turned_scaled_shifted_view(pair):
    """The best coarse hypothesis lands near the pair's true transform (a random similarity with a keystone), and
    stands far out of the scores searched; the runner-up is elsewhere."""
    from rgbt_toolkit.registration.coarse import coarse_search
    from rgbt_toolkit.registration.transforms import corner_error

    visible, thermal, truth = pair
    h, w = visible.shape[:2]
    scales, angles = np.exp(np.arange(-0.4, 0.45, 0.06)), np.deg2rad(np.arange(-6.0, 6.5, 1.0))
    found = coarse_search([to_grey(visible)], [to_grey(thermal)], scales, angles, work_size=256)
    assert found[0].z > 5 and found[0].z > found[1].z + 2
    assert corner_error(found[0].matrix, truth, (w, h)) < 6  # within a grid cell; ECC refines from there
    assert corner_error(found[1].matrix, truth, (w, h)) > 10


def test_coarse_search_is_the_same_on_one_or_two_threads(pair):
    import cv2

    from rgbt_toolkit.registration.coarse import coarse_search

    visible, thermal = to_grey(pair[0]), to_grey(pair[1])
    scales, angles = np.exp(np.linspace(-0.2, 0.2, 5)), np.deg2rad([-2.0, 0.0, 2.0])
    results = []
    for threads in (1, 2):
        cv2.setNumThreads(threads)
        results.append(coarse_search([visible], [thermal], scales, angles, keep=3))
    cv2.setNumThreads(1)
    assert [c.score for c in results[0]] == [c.score for c in results[1]]
    assert all(np.allclose(a.matrix, b.matrix) for a, b in zip(*results))


def test_equalised_copy_brings_out_the_dark_scene_beside_street_lamps():
    """A night frame: saturated lamps set the global gradient scale, so the faint texture of the dark scene barely
    registers in the orientation field; in the locally equalised copy it does (FLIR_06997's darker 60 %: mean
    magnitude 0.07 -> 0.13)."""
    import cv2

    from rgbt_toolkit.registration.features import equalised

    noise = cv2.GaussianBlur(np.random.default_rng(0).random((128, 256)).astype(np.float32), (0, 0), 3)
    grey = (0.03 + 0.06 * (noise - noise.min()) / (noise.max() - noise.min())).astype(np.float32)
    for k in range(4):
        grey[10 + 20 * k:22 + 20 * k, 200:212] = 1.0  # lamps

    def magnitude(image):
        return np.hypot(*np.moveaxis(orientation_field(image), 2, 0))[:, :150].mean()  # the dark scene only

    flat = equalised(grey)
    assert magnitude(flat) > 3 * magnitude(grey)
    assert flat.dtype == np.float32 and 0.0 <= flat.min() <= flat.max() <= 1.0


def test_dead_pixels_of_a_radiometric_frame_do_not_set_the_range():
    frame = np.linspace(300, 340, 100 * 100, dtype=np.float32).reshape(100, 100)  # kelvin
    frame.flat[::50] = np.nan
    grey = to_grey(frame)
    alive = np.isfinite(frame)
    assert grey[alive].min() < 0.01 and grey[alive].max() > 0.99  # the live pixels keep the whole contrast
    assert np.isfinite(grey).all()


def _texture(shape, seed=0):
    import cv2

    noise = np.random.default_rng(seed).random(shape).astype(np.float32)
    return cv2.normalize(cv2.GaussianBlur(noise, (0, 0), 2.0), None, 0.1, 0.9, cv2.NORM_MINMAX)


def test_fill_mask_finds_black_bars_of_a_warped_frame():
    """A frame warped by an earlier step (rotated and shifted, black outside) has a fill of straight edges."""
    import cv2

    from rgbt_toolkit.registration.features import fill_mask

    image = _texture((240, 320))
    turn = cv2.getRotationMatrix2D((160, 120), 4.0, 1.0)
    turn[:, 2] += (14, -10)
    warped = cv2.warpAffine(image, turn, (320, 240), flags=cv2.INTER_LINEAR, borderValue=0.0)
    outside = cv2.warpAffine(np.ones((240, 320), np.float32), turn, (320, 240), flags=cv2.INTER_NEAREST) == 0
    mask = fill_mask(warped)
    assert mask is not None
    overlap = (mask & outside).sum() / (mask | outside).sum()
    assert overlap > 0.9, f"fill found {mask.mean():.3f} vs {outside.mean():.3f} of the frame, IoU {overlap:.2f}"


def test_fill_mask_finds_a_frame_pasted_on_a_page():
    from rgbt_toolkit.registration.features import fill_mask

    page = np.full((240, 320), 252 / 255, np.float32)
    page[30:210, 40:290] = _texture((180, 250), 1)
    mask = fill_mask(page)
    assert mask is not None and abs(mask.mean() - (1 - 180 * 250 / (240 * 320))) < 0.01


def test_fill_mask_leaves_a_clipped_sky_and_small_patches_alone():
    """A cold sky clipped to 0 above a ragged treeline is scene, not fill: its outline is real structure."""
    from rgbt_toolkit.registration.features import fill_mask

    image = _texture((240, 320), 2)
    horizon = 80 + np.cumsum(np.random.default_rng(3).integers(-3, 4, 320))
    rows = np.arange(240)[:, None]
    sky = image.copy()
    sky[rows < horizon[None, :]] = 0.0
    assert fill_mask(sky) is None
    patch = image.copy()
    patch[:6, 100:160] = 1.0  # a clipped highlight at the top edge, 0.5 % of the frame
    assert fill_mask(patch) is None
    assert fill_mask(image) is None


def test_orientation_field_ignores_the_edge_of_a_fill():
    image = _texture((240, 320), 4)
    image[:, :40] = 0.0  # a black bar on the left
    near_edge = np.s_[20:-20, 36:44]
    assert np.abs(orientation_field(image, ignore_fill=False)[near_edge]).max() > 0.5
    # what is left near the bar's edge is the scene's own texture, leaking in through the 1-px smoothing
    assert np.abs(orientation_field(image)[:, :36]).max() < 0.3
    assert np.abs(orientation_field(image)[:, :30]).max() == 0.0
