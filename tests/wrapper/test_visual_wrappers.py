"""Pixel-perturbation wrappers (stable_worldmodel.wrapper.visual) and MapKeysWrapper.

Behaviour follows upstream stable-worldmodel 0.1.1 as observed by running it side by side on the
same small frames: which keys change (``render()``, ``info["pixels"]``, ``info["pixels.<view>"]``;
never ``goal``), dtypes and shapes, when random draws happen (per frame, per reset, at
construction), and the exact outputs for a constructor ``seed`` (the pinned numbers below are
upstream 0.1.1's outputs). Two deliberate differences are tested too: with ``seed=None`` a
``reset(seed=s)`` seeds the wrapper's generator (Gymnasium's convention; upstream stayed
unseeded), and moving patches always stay inside the frame (upstream's single reflection
per step let a fast patch leave it). Bad arguments raise typed errors.
"""

from __future__ import annotations

import pickle

import gymnasium as gym
import numpy as np
import pytest

import stable_worldmodel as swm
from stable_worldmodel import keys
from stable_worldmodel.envs.toy import ToyEnv
from stable_worldmodel.errors import ConfigError, SpaceError, UnknownNameError
from stable_worldmodel.wrapper import (
    AddPixelsWrapper,
    BlurWrapper,
    ChromaKeyWrapper,
    ColorJitterWrapper,
    CutoutWrapper,
    GrayscaleWrapper,
    MapKeysWrapper,
    MovingPatchWrapper,
    NoiseWrapper,
    OcclusionWrapper,
    RandomConvWrapper,
    RandomShiftWrapper,
    ResolutionWrapper,
    constant,
    cosine,
    exponential,
    linear,
    sinusoidal,
)

GREEN = (0, 255, 0)


def ramp(h: int = 8, w: int = 8, t: int = 0) -> np.ndarray:
    """A deterministic (h, w, 3) uint8 frame that changes with ``t``."""
    return ((np.arange(h * w * 3).reshape(h, w, 3) * 7 + t * 13) % 256).astype(np.uint8)


class Frames(gym.Env):
    """Frames are ``ramp(h, w, t)``; reset info has ``pixels``, ``pixels.top``, ``goal`` and ``x``; step info has
    ``pixels`` and ``goal``. ``render_views`` makes ``render()`` return a dict of two views."""

    observation_space = gym.spaces.Box(0, 1, (2,), np.float32)
    action_space = gym.spaces.Box(-1, 1, (2,), np.float32)

    def __init__(self, h: int = 8, w: int = 8, render_views: bool = False, frame=None):
        self.h, self.w, self.t = h, w, 0
        self.render_views = render_views
        self.frame_fn = frame or (lambda t: ramp(h, w, t))
        self.last_info: dict | None = None

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.t = 0
        self.last_info = {
            keys.PIXELS: self.frame_fn(0),
            f"{keys.PIXELS}.top": self.frame_fn(1),
            keys.GOAL: self.frame_fn(2),
            "x": 1,
        }
        return np.zeros(2, np.float32), self.last_info

    def step(self, action):
        self.t += 1
        self.last_info = {keys.PIXELS: self.frame_fn(self.t), keys.GOAL: self.frame_fn(2)}
        return np.zeros(2, np.float32), 0.0, False, False, self.last_info

    def render(self):
        img = self.frame_fn(self.t)
        return {"a": img, "b": img.copy()} if self.render_views else img


def checksum(img) -> tuple[int, int]:
    """(sum, position-weighted sum) of an image: pins every pixel value cheaply."""
    a = np.asarray(img).astype(np.int64)
    return int(a.sum()), int((a * np.arange(a.size).reshape(a.shape)).sum())


def pixels_over_episode(w: gym.Env, steps: int = 1) -> list[np.ndarray]:
    _, info = w.reset()
    out = [info[keys.PIXELS]]
    for _ in range(steps):
        out.append(w.step(np.zeros(2))[4][keys.PIXELS])
    return out


ALL = [
    lambda env: ChromaKeyWrapper(env, (0, 0, 0), np.full((4, 4, 3), 9, np.uint8), tolerance=500),
    lambda env: NoiseWrapper(env, seed=0),
    lambda env: ColorJitterWrapper(env, seed=0),
    lambda env: BlurWrapper(env),
    lambda env: OcclusionWrapper(env, size=(0.5, 0.5), seed=0),
    lambda env: MovingPatchWrapper(env, size=(0.5, 0.5), seed=0),
    lambda env: RandomShiftWrapper(env, pad=2, seed=0),  # no draw of the identity offset (2, 2)
    lambda env: CutoutWrapper(env, size=(0.5, 0.5), seed=0),
    lambda env: RandomConvWrapper(env, seed=0),
    lambda env: GrayscaleWrapper(env),
    lambda env: ResolutionWrapper(env),
]


# -- what every wrapper touches ---------------------------------------------------------------------
@pytest.mark.parametrize("make", ALL)
def test_pixels_views_and_render_change_goal_and_others_do_not(make):
    env = Frames()
    w = make(env)
    _, info = w.reset()
    assert set(info) == {keys.PIXELS, f"{keys.PIXELS}.top", keys.GOAL, "x"}
    assert not np.array_equal(info[keys.PIXELS], ramp(t=0))
    assert not np.array_equal(info[f"{keys.PIXELS}.top"], ramp(t=1))
    assert info[keys.GOAL] is env.last_info[keys.GOAL] and info["x"] == 1
    assert info[keys.PIXELS].dtype == np.uint8
    info = w.step(np.zeros(2))[4]
    assert not np.array_equal(info[keys.PIXELS], ramp(t=1))
    assert np.array_equal(info[keys.GOAL], ramp(t=2))
    assert not np.array_equal(w.render(), ramp(t=1))


@pytest.mark.parametrize("make", ALL)
def test_render_views_and_none_are_handled(make):
    views = make(Frames(render_views=True)).render()
    assert set(views) == {"a", "b"} and all(v.shape[:2] == (8, 8) for v in views.values())

    class NoRender(Frames):
        def render(self):
            return None

    assert make(NoRender()).render() is None


# -- NoiseWrapper and the schedules -------------------------------------------------------------------
def test_noise_matches_upstream_for_a_seed():
    out = pixels_over_episode(NoiseWrapper(Frames(), seed=0))
    assert [checksum(o) for o in out] == [(23578, 2309729), (23569, 2285110)]  # upstream 0.1.1, seed=0
    assert out[0].reshape(-1)[:6].tolist() == [1, 5, 20, 22, 22, 38]


def test_noise_schedule_sees_the_step_count_and_reset_keeps_it():
    calls = []
    w = NoiseWrapper(Frames(), std=lambda step: calls.append(step) or 0.0, seed=0)
    w.reset()  # pixels, pixels.top
    w.render()
    w.step(0)  # a step's own frames use the count before the step
    w.step(0)
    w.render()
    w.reset()
    assert calls == [0, 0, 0, 0, 1, 2, 2, 2]  # as upstream 0.1.1
    assert w.step_count == 2


def test_noise_std_zero_leaves_frames_and_float_frames_keep_dtype():
    _, info = NoiseWrapper(Frames(), std=0.0, seed=0).reset()
    assert np.array_equal(info[keys.PIXELS], ramp())
    env = Frames(frame=lambda t: ramp(t=t).astype(np.float32))
    out = NoiseWrapper(env, std=20.0, seed=0).reset()[1][keys.PIXELS]
    assert out.dtype == np.float32 and out.min() >= 0 and out.max() <= 255 and not np.array_equal(out, ramp())


def test_schedules_values_and_pickle():
    assert constant(3.0)(100) == 3.0
    assert linear(0, 10, 5)(2) == 4.0 and linear(0, 10, 5)(99) == 10 and linear(0, 10, 0)(0) == 0.0
    assert cosine(0, 10, 4)(2) == pytest.approx(5.0) and cosine(0, 10, 4)(0) == 0.0 and cosine(0, 10, 4)(9) == 10
    assert exponential(8, 0.5, 1.0)(5) == 1.0 and exponential(8, 0.5)(2) == 2.0
    assert sinusoidal(0, 2, 4)(1) == 2.0 and sinusoidal(0, 2, 4)(0) == 1.0
    assert pickle.loads(pickle.dumps(linear(0, 10, 5)))(2) == 4.0


# -- seeding ------------------------------------------------------------------------------------------
def test_constructor_seed_is_reproducible_and_not_reseeded_by_reset():
    a = pixels_over_episode(CutoutWrapper(Frames(), seed=4), steps=3)
    b = pixels_over_episode(CutoutWrapper(Frames(), seed=4), steps=3)
    assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    w = NoiseWrapper(Frames(), seed=4)
    first = w.reset(seed=1)[1][keys.PIXELS]
    again = w.reset(seed=1)[1][keys.PIXELS]
    assert not np.array_equal(first, again)  # constructor seed wins: the stream goes on, as upstream


def test_unseeded_wrapper_is_seeded_by_reset_seed():
    a, b = NoiseWrapper(Frames()), NoiseWrapper(Frames())
    x = a.reset(seed=5)[1][keys.PIXELS]
    assert np.array_equal(x, b.reset(seed=5)[1][keys.PIXELS])
    assert np.array_equal(x, NoiseWrapper(Frames(), seed=5).reset()[1][keys.PIXELS])
    assert np.array_equal(x, a.reset(seed=5)[1][keys.PIXELS])  # every seeded reset restarts the stream
    assert not np.array_equal(x, a.reset(seed=6)[1][keys.PIXELS])


# -- ColorJitterWrapper -------------------------------------------------------------------------------
def test_color_jitter_matches_upstream_and_redraws_at_reset():
    w = ColorJitterWrapper(Frames(), seed=0)
    assert w.brightness_factor == pytest.approx(1.0547846749285816)  # drawn at construction, as upstream
    assert w.hue_shift == pytest.approx(-0.04834723644714709)
    out = pixels_over_episode(w)
    assert [checksum(o) for o in out] == [(25625, 2520424), (25637, 2491273)]
    assert (w.brightness_factor, w.contrast_factor, w.saturation_factor, w.hue_shift) == pytest.approx(
        (1.125308095680109, 1.1651022309110886, 1.042654310306872, 0.022949656098399843)
    )
    assert 0.8 <= w.brightness_factor <= 1.2 and abs(w.hue_shift) <= 0.05
    factors = (w.brightness_factor, w.hue_shift)
    w.step(0)
    assert (w.brightness_factor, w.hue_shift) == factors  # fixed within an episode


def test_color_jitter_with_zero_strength_is_only_the_hsv_round_trip():
    w = ColorJitterWrapper(Frames(), 0, 0, 0, 0, seed=0)
    assert (w.brightness_factor, w.contrast_factor, w.saturation_factor, w.hue_shift) == (1.0, 1.0, 1.0, 0.0)
    out = pixels_over_episode(w)
    assert [checksum(o) for o in out] == [(23647, 2323026), (23585, 2283559)]  # upstream 0.1.1


# -- BlurWrapper --------------------------------------------------------------------------------------
def test_blur_matches_upstream_and_kernel_is_made_odd():
    assert [checksum(o) for o in pixels_over_episode(BlurWrapper(Frames()))] == [(23396, 2218556), (23596, 2229016)]
    w = BlurWrapper(Frames(), kernel=4, sigma=1.0)
    assert w.kernel == 5
    assert checksum(pixels_over_episode(w)[0]) == (23393, 2222359)
    assert np.array_equal(BlurWrapper(Frames(), kernel=0).reset()[1][keys.PIXELS], ramp())  # 1x1 kernel


# -- OcclusionWrapper / CutoutWrapper -----------------------------------------------------------------
def test_occlusion_patches_fixed_per_episode_and_redrawn_at_reset():
    w = OcclusionWrapper(Frames(16, 16), seed=0)
    _, info = w.reset()
    assert w.patches == [(4, 0, 3, 2)]  # (top, left, height, width), as upstream 0.1.1 with seed=0
    assert (info[keys.PIXELS][4:7, 0:2] == 0).all() and info[keys.PIXELS].sum() > 0
    first = w.step(0)[4][keys.PIXELS]
    assert w.patches == [(4, 0, 3, 2)] and (first[4:7, 0:2] == 0).all()
    w.reset()
    assert w.patches == [(10, 11, 1, 4)]


def test_occlusion_color_and_several_patches():
    w = OcclusionWrapper(Frames(16, 16), num_patches=2, size=(0.25, 0.5), color=(255, 0, 0), seed=1)
    _, info = w.reset()
    assert w.patches == [(0, 1, 6, 7), (8, 5, 7, 5)]
    assert (info[keys.PIXELS][0:6, 1:8] == (255, 0, 0)).all() and (info[keys.PIXELS][8:15, 5:10] == (255, 0, 0)).all()


def test_cutout_draws_new_rectangles_for_every_frame():
    out = pixels_over_episode(CutoutWrapper(Frames(16, 16), num=2, size=(0.25, 0.5), seed=0), steps=2)
    assert [checksum(o) for o in out] == [(75834, 29738998), (75782, 31469476), (76995, 30712613)]  # upstream
    assert CutoutWrapper(Frames(), num=0, seed=0).render() is not None
    assert np.array_equal(CutoutWrapper(Frames(), num=0, seed=0).render(), ramp())


# -- MovingPatchWrapper -------------------------------------------------------------------------------
def test_moving_patch_matches_upstream_and_moves_after_each_step():
    w = MovingPatchWrapper(Frames(16, 16), num_patches=2, size=(0.25, 0.25), speed=3.0, seed=3)
    _, info = w.reset()
    assert w.patches[0][:4] == pytest.approx([9.615293582476763, 6.985944432772413, 4, 4])
    assert (info[keys.PIXELS][9:13, 6:10] == 255).all()
    before = [p[:2] for p in w.patches]
    step_info = w.step(0)[4]
    assert (step_info[keys.PIXELS][9:13, 6:10] == 255).all()  # a step's frames show the patches before the move
    for (y0, x0), p in zip(before, w.patches, strict=True):
        assert np.hypot(p[0] - y0, p[1] - x0) == pytest.approx(3.0)  # no bounce yet: one move of `speed`
    for _ in range(4):
        w.step(0)
    expected = [
        [6.021504551326842, 4.561872845100144, 4, 4, -1.6726403732392787, -2.490436544425488],
        [11.742317454151554, 3.851031528572273, 4, 4, 1.9650900957013222, -2.2668085309034307],
    ]  # upstream 0.1.1 after 5 steps (both patches bounced)
    assert [p for p in w.patches] == [pytest.approx(e) for e in expected]


def test_moving_patch_stays_in_the_frame_when_faster_than_the_frame():
    w = MovingPatchWrapper(Frames(16, 16), size=(0.3, 0.3), speed=40.0, seed=1)
    w.reset()
    for _ in range(5):
        info = w.step(0)[4]
        y, x, h, wd = w.patches[0][:4]
        assert 0 <= y <= 16 - h and 0 <= x <= 16 - wd
        assert (info[keys.PIXELS] == 255).all(-1).sum() >= h * wd  # upstream 0.1.1 lost the patch here


# -- RandomShiftWrapper -------------------------------------------------------------------------------
def test_random_shift_is_a_crop_of_the_edge_padded_frame():
    w = RandomShiftWrapper(Frames(), pad=2, seed=0)
    out = pixels_over_episode(w)
    assert [checksum(o) for o in out] == [(24296, 2215920), (19784, 2016720)]  # upstream 0.1.1
    padded = np.pad(ramp(), [(2, 2), (2, 2), (0, 0)], mode="edge")
    assert np.array_equal(out[0], padded[4:12, 3:11])  # offsets (dy, dx) = first two draws (4, 3)
    assert np.array_equal(RandomShiftWrapper(Frames(), pad=0, seed=0).render(), ramp())


# -- RandomConvWrapper --------------------------------------------------------------------------------
def test_random_conv_matches_upstream_and_redraws_weights_at_reset():
    w = RandomConvWrapper(Frames(), kernel_size=2, seed=0)
    assert w.kernel_size == 3 and w.weights.shape == (3, 3, 3, 3) and w.weights.dtype == np.float32
    assert w.weights[0, 0, 0].tolist() == pytest.approx(
        [0.024196792393922806, -0.02542359195649624, 0.12324939668178558]
    )
    first = w.weights.copy()
    out = pixels_over_episode(w)
    assert not np.array_equal(first, w.weights)
    assert [checksum(o) for o in out] == [(2321, 251054), (2341, 237513)]  # upstream 0.1.1, seed=0
    assert [checksum(o) for o in pixels_over_episode(RandomConvWrapper(Frames(), seed=7))] == [
        (330, 34068),
        (176, 20407),
    ]


# -- GrayscaleWrapper / ResolutionWrapper -------------------------------------------------------------
def test_grayscale_luma_and_channels():
    rgb = np.array([[[255, 0, 0], [0, 255, 0], [0, 0, 255]]], np.uint8)
    env = Frames(frame=lambda t: rgb)
    keep = GrayscaleWrapper(env).render()
    assert keep.shape == (1, 3, 3) and keep[0, :, 0].tolist() == [76, 150, 29]
    assert (keep == keep[..., :1]).all()
    assert GrayscaleWrapper(env, keep_channels=False).render().tolist() == [[76, 150, 29]]
    assert checksum(GrayscaleWrapper(Frames()).reset()[1][keys.PIXELS]) == (23766, 2334426)  # upstream 0.1.1


def test_resolution_is_blocky_and_keeps_the_size():
    out = ResolutionWrapper(Frames()).reset()[1][keys.PIXELS]
    assert out.shape == (8, 8, 3) and checksum(out) == (23744, 2321248)  # upstream 0.1.1
    blocks = out.reshape(4, 2, 4, 2, 3)
    assert (blocks == blocks[:, :1, :, :1]).all()  # 2x2 blocks of one colour
    assert checksum(ResolutionWrapper(Frames(), scale=0.3).reset()[1][keys.PIXELS]) == (23680, 2317632)
    checker = np.indices((8, 8)).sum(0) % 2 * 255
    env = Frames(frame=lambda t: np.repeat(checker[..., None], 3, -1).astype(np.uint8))
    assert np.unique(ResolutionWrapper(env, scale=0.5).render()).tolist() == [128]  # INTER_AREA averages


# -- ChromaKeyWrapper ---------------------------------------------------------------------------------
def keyed_frame(t=0):
    f = np.full((8, 8, 3), 100, np.uint8)
    f[:4] = GREEN
    f[4, :2] = (5, 250, 3)  # near green: distance sqrt(25 + 25 + 9) ~ 7.7
    return f


def test_chroma_key_replaces_exact_and_near_key_pixels_with_the_image():
    bg = np.full((8, 8, 3), 7, np.uint8)
    exact = ChromaKeyWrapper(Frames(frame=keyed_frame), GREEN, bg).render()
    assert (exact[:4] == 7).all() and (exact[4:] == keyed_frame()[4:]).all()
    near = ChromaKeyWrapper(Frames(frame=keyed_frame), [GREEN, (1, 1, 1)], bg, tolerance=8).render()
    assert (near[:4] == 7).all() and (near[4, :2] == 7).all() and (near[4, 2:] == 100).all()
    big = np.arange(16 * 16 * 3).reshape(16, 16, 3).astype(np.uint8)  # resized (INTER_AREA) to the frame
    import cv2

    expected = cv2.resize(big, (8, 8), interpolation=cv2.INTER_AREA)
    assert np.array_equal(ChromaKeyWrapper(Frames(frame=keyed_frame), GREEN, big).render()[:4], expected[:4])


def test_chroma_key_video_advances_per_frame_and_loops():
    video = np.stack([np.full((8, 8, 3), v, np.uint8) for v in (10, 20, 30)])
    w = ChromaKeyWrapper(Frames(frame=keyed_frame), GREEN, video)
    _, info = w.reset()  # pixels, then pixels.top: two video frames
    seen = [info[keys.PIXELS][0, 0, 0], info[f"{keys.PIXELS}.top"][0, 0, 0]]
    seen += [w.render()[0, 0, 0], w.step(0)[4][keys.PIXELS][0, 0, 0]]
    w.reset()  # does not restart the video: pixels and pixels.top take 20 and 30
    assert seen == [10, 20, 30, 10] and w.render()[0, 0, 0] == 10


def test_chroma_key_reads_media_files(tmp_path):
    import imageio.v3 as iio

    iio.imwrite(tmp_path / "bg.png", np.full((8, 8, 3), 42, np.uint8))
    out = ChromaKeyWrapper(Frames(frame=keyed_frame), GREEN, str(tmp_path / "bg.png")).render()
    assert (out[:4] == 42).all()
    with pytest.raises(FileNotFoundError):
        ChromaKeyWrapper(Frames(), GREEN, tmp_path / "missing.png")


# -- MapKeysWrapper -----------------------------------------------------------------------------------
def test_map_keys_renames_in_order_on_reset_and_step():
    w = MapKeysWrapper(Frames(), {keys.PIXELS: "img", "img": "img2", keys.GOAL: keys.PIXELS})
    _, info = w.reset()
    assert list(info) == [f"{keys.PIXELS}.top", "x", "img2", keys.PIXELS]  # as upstream 0.1.1
    assert np.array_equal(info["img2"], ramp(t=0)) and np.array_equal(info[keys.PIXELS], ramp(t=2))
    info = MapKeysWrapper(Frames(), [(keys.PIXELS, "observation")]).step(0)[4]
    assert set(info) == {"observation", keys.GOAL}


def test_map_keys_missing_key_is_a_key_error_naming_it():
    w = MapKeysWrapper(Frames(), {"pixel": "img"})
    with pytest.raises(KeyError, match="key 'pixel' not found in info") as err:
        w.reset()
    assert isinstance(err.value, UnknownNameError) and "Did you mean" in str(err.value)


# -- argument errors ----------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "make, exc, words",
    [
        (lambda e: NoiseWrapper(e, std=-1.0), ConfigError, "std"),
        (lambda e: NoiseWrapper(e, seed=-1), ConfigError, "seed"),
        (lambda e: NoiseWrapper(e, seed="a"), TypeError, "seed"),
        (lambda e: ColorJitterWrapper(e, brightness=-0.5), ConfigError, "brightness"),
        (lambda e: BlurWrapper(e, kernel=-5), ConfigError, "kernel"),
        (lambda e: BlurWrapper(e, kernel=2.5), ConfigError, "kernel"),
        (lambda e: OcclusionWrapper(e, size=0.2), ConfigError, "size"),
        (lambda e: OcclusionWrapper(e, size=(0.5, 0.1)), ConfigError, "size"),
        (lambda e: OcclusionWrapper(e, num_patches=-1), ConfigError, "num_patches"),
        (lambda e: OcclusionWrapper(e, color=[[1, 2, 3]]), ConfigError, "color"),
        (lambda e: MovingPatchWrapper(e, speed=float("nan")), ConfigError, "speed"),
        (lambda e: RandomShiftWrapper(e, pad=-1), ConfigError, "pad"),
        (lambda e: CutoutWrapper(e, num=-2), ConfigError, "num"),
        (lambda e: RandomConvWrapper(e, kernel_size=-3), ConfigError, "kernel_size"),
        (lambda e: ResolutionWrapper(e, scale=0), ConfigError, "scale"),
        (lambda e: ChromaKeyWrapper(e, (0, 255), np.zeros((4, 4, 3))), ConfigError, "key_color"),
        (lambda e: ChromaKeyWrapper(e, GREEN, np.zeros((4, 4))), ConfigError, "media"),
        (lambda e: ChromaKeyWrapper(e, GREEN, np.zeros((0, 4, 4, 3))), ConfigError, "media"),
        (lambda e: ChromaKeyWrapper(e, GREEN, np.zeros((4, 4, 3)), tolerance=-1), ConfigError, "tolerance"),
        (lambda e: MapKeysWrapper(e, 5), TypeError, "key_map"),
    ],
)
def test_bad_arguments_raise_typed_errors(make, exc, words):
    with pytest.raises(exc, match=words):
        make(Frames())


@pytest.mark.parametrize("make", [ColorJitterWrapper, GrayscaleWrapper, RandomConvWrapper])
def test_rgb_only_wrappers_refuse_other_frames(make):
    with pytest.raises(SpaceError, match=r"\(H, W, 3\)"):
        make(Frames(frame=lambda t: np.zeros((8, 8), np.uint8))).render()


# -- exports and use in a pipeline --------------------------------------------------------------------
def test_names_are_exported_from_both_spellings():
    names = [
        "ChromaKeyWrapper",
        "NoiseWrapper",
        "ColorJitterWrapper",
        "BlurWrapper",
        "OcclusionWrapper",
        "MovingPatchWrapper",
        "RandomShiftWrapper",
        "CutoutWrapper",
        "RandomConvWrapper",
        "GrayscaleWrapper",
        "ResolutionWrapper",
        "MapKeysWrapper",
        "constant",
        "linear",
        "cosine",
        "exponential",
        "sinusoidal",
    ]
    for name in names:
        assert name in swm.wrapper.__all__ and getattr(swm.wrappers, name) is getattr(swm.wrapper, name)


def test_perturbs_the_pixels_of_a_pixel_pipeline():
    env = GrayscaleWrapper(AddPixelsWrapper(ToyEnv(), pixels_shape=(16, 16)), keep_channels=False)
    _, info = env.reset(seed=0)
    assert info[keys.PIXELS].shape == (16, 16) and info[keys.PIXELS].dtype == np.uint8
    assert env.step(np.zeros(2, np.float32))[4][keys.PIXELS].shape == (16, 16)
