"""Keyframe curves (ecs_engine/animation/sampling.py) against the glTF specification's formulas
(its Appendix C) written out here key by key in plain Python, at many times inside and outside
the keys: STEP, LINEAR (slerp for rotations, the shorter way round), CUBICSPLINE; and clips read
from glTF files (render/assets/gltf/clips.py), whose broken samplers are one error naming the
file and the field."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from gltf_files import GltfBuilder

from ecs_engine.animation import CUBICSPLINE, LINEAR, STEP, Curve
from ecs_engine.render.assets.gltf import GltfDocument, GltfError
from ecs_engine.render.assets.gltf.clips import read_clips

TIMES = np.array([0.5, 1.0, 1.75, 3.0])
PROBES = np.concatenate([np.linspace(-1.0, 4.0, 41), TIMES, TIMES + 1e-9, TIMES - 1e-9])


def key_of(times, t):
    """The key interval a time falls in, and the time clamped to the keys."""
    t = min(max(t, times[0]), times[-1])
    k = 0
    while k < len(times) - 2 and t >= times[k + 1]:
        k += 1
    return k, t


def reference_step(times, values, t):
    k, t = key_of(times, t)
    return values[k + 1] if t >= times[k + 1] else values[k]


def reference_linear(times, values, t):
    k, t = key_of(times, t)
    s = (t - times[k]) / (times[k + 1] - times[k])
    return [(1 - s) * a + s * b for a, b in zip(values[k], values[k + 1])]


def reference_slerp(times, values, t):
    k, t = key_of(times, t)
    s = (t - times[k]) / (times[k + 1] - times[k])
    a, b = values[k], values[k + 1]
    dot = sum(x * y for x, y in zip(a, b))
    angle = math.acos(min(abs(dot), 1.0))
    if angle < 1e-9:
        return list(a)
    sign = 1.0 if dot >= 0 else -1.0
    return [
        math.sin(angle * (1 - s)) / math.sin(angle) * x + sign * math.sin(angle * s) / math.sin(angle) * y
        for x, y in zip(a, b)
    ]


def reference_cubic(times, a_in, v, b_out, t):
    k, t = key_of(times, t)
    td = times[k + 1] - times[k]
    s = (t - times[k]) / td
    h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
    h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
    return [
        h00 * v[k][i] + td * h10 * b_out[k][i] + h01 * v[k + 1][i] + td * h11 * a_in[k + 1][i] for i in range(len(v[k]))
    ]


def unit(rows):
    rows = np.asarray(rows, np.float64)
    return rows / np.linalg.norm(rows, axis=1, keepdims=True)


def test_step_and_linear_curves_match_the_specification_everywhere():
    rng = np.random.default_rng(5)
    values = rng.normal(size=(4, 3))
    for interpolation, reference in ((STEP, reference_step), (LINEAR, reference_linear)):
        got = Curve(TIMES, values, interpolation).sample(PROBES)
        want = np.array([reference(TIMES, values.tolist(), t) for t in PROBES])
        np.testing.assert_allclose(got, want, atol=1e-12)


def test_rotations_slerp_the_shorter_way_and_stay_unit():
    rng = np.random.default_rng(6)
    q = unit(rng.normal(size=(4, 4)))
    q[2] = -q[1] * 0.999 + 0.01  # nearly the same rotation as key 1, written with the other sign
    q = unit(q)
    got = Curve(TIMES, q, LINEAR, rotation=True).sample(PROBES)
    want = np.array([reference_slerp(TIMES, q.tolist(), t) for t in PROBES])
    np.testing.assert_allclose(got, want, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(got, axis=1), 1.0, atol=1e-12)
    between = Curve(TIMES, q, LINEAR, rotation=True).sample(np.linspace(1.0, 1.75, 9))
    assert np.abs(np.sum(between * q[1], axis=1)).min() > 0.99  # the short way: never far from key 1


def test_cubic_splines_match_the_hermite_formula_with_scaled_tangents():
    rng = np.random.default_rng(7)
    a_in, v, b_out = rng.normal(size=(3, 4, 3))
    got = Curve(TIMES, v, CUBICSPLINE, in_tangents=a_in, out_tangents=b_out).sample(PROBES)
    want = np.array([reference_cubic(TIMES, a_in.tolist(), v.tolist(), b_out.tolist(), t) for t in PROBES])
    np.testing.assert_allclose(got, want, atol=1e-12)
    q = Curve(TIMES, unit(rng.normal(size=(4, 4))), CUBICSPLINE, True, rng.normal(size=(4, 4)), rng.normal(size=(4, 4)))
    np.testing.assert_allclose(np.linalg.norm(q.sample(PROBES), axis=1), 1.0, atol=1e-12)


def test_one_key_holds_at_all_times():
    curve = Curve(np.array([2.0]), np.array([[1.0, 2.0, 3.0]]), LINEAR)
    np.testing.assert_array_equal(curve.sample([-5.0, 2.0, 9.0]), [[1.0, 2.0, 3.0]] * 3)


def clip_file(tmp_path, edit=None):
    b = GltfBuilder()
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0]], np.float32)
    mover = b.node("mover", mesh=b.mesh([b.primitive(square)]))
    q = unit([[0, 0, 0, 1], [0, 0.6, 0, 0.8], [0, 1, 0, 0], [0.6, 0, 0, 0.8]])
    cubic = np.stack([np.full((4, 3), 0.5), np.arange(12.0).reshape(4, 3), np.full((4, 3), -0.5)], axis=1)
    b.animation(
        [
            (mover, "translation", TIMES, np.arange(12.0).reshape(4, 3), LINEAR),
            (mover, "rotation", TIMES, q, LINEAR),
            (mover, "scale", TIMES, cubic, CUBICSPLINE),
        ],
        name="walk",
    )
    b.scene([mover])
    path = b.gltf(tmp_path / "clip.gltf")
    if edit is not None:
        document = json.loads(path.read_text())
        edit(document, b)
        path.write_text(json.dumps(document))
    return path, q, cubic


def test_a_files_clip_samples_what_its_keys_say(tmp_path):
    path, q, cubic = clip_file(tmp_path)
    (clip,) = read_clips(GltfDocument.read(path))
    assert clip.name == "walk" and clip.duration == pytest.approx(3.0)
    move, turn, grow = clip.channels
    assert (move.path, turn.path, grow.path) == ("translation", "rotation", "scale")
    np.testing.assert_allclose(move.curve.sample(1.375), [4.5, 5.5, 6.5], atol=1e-5)  # halfway from key 1 to 2
    want = reference_slerp(TIMES, q.tolist(), 2.0)
    np.testing.assert_allclose(turn.curve.sample(2.0), want, atol=1e-6)
    want = reference_cubic(TIMES, cubic[:, 0].tolist(), cubic[:, 1].tolist(), cubic[:, 2].tolist(), 1.2)
    np.testing.assert_allclose(grow.curve.sample(1.2), want, atol=1e-5)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d, b: d["animations"][0]["channels"][0]["target"].update(node=9), r"channels\[0\]\.target\.node"),
        (lambda d, b: d["animations"][0]["channels"][1]["target"].update(path="color"), r"target\.path"),
        (lambda d, b: d["animations"][0]["samplers"][0].update(interpolation="SMOOTH"), r"interpolation"),
        (
            lambda d, b: d["animations"][0]["samplers"][0].update(output=d["animations"][0]["samplers"][2]["output"]),
            r"samplers\[0\]\.output: holds",
        ),
        (lambda d, b: d["animations"][0]["samplers"][0].update(input=0), r"samplers\[0\]\.input"),
    ],
)
def test_a_broken_clip_is_one_error_naming_the_file_and_the_field(tmp_path, edit, message):
    path, _, _ = clip_file(tmp_path, edit)
    with pytest.raises(GltfError, match=message) as caught:
        read_clips(GltfDocument.read(path))
    assert str(path) in str(caught.value)


def test_times_that_decrease_are_one_error_naming_the_key(tmp_path):
    b = GltfBuilder()
    node = b.node("n")
    b.animation([(node, "translation", [0.0, 1.0, 0.5], np.zeros((3, 3)), LINEAR)])
    b.scene([node])
    with pytest.raises(GltfError, match=r"animations\[0\]\.samplers\[0\]\.input: times do not increase at key 2"):
        read_clips(GltfDocument.read(b.gltf(tmp_path / "back.gltf")))


def test_writing_a_linear_curve_in_place_matches_sampling_it():
    from ecs_engine.animation.sampling import LINEAR, Curve
    from ecs_engine.animation.write_linear import write_sampled

    rng = np.random.default_rng(9)
    times = np.array([0.0, 0.4, 1.0, 1.7])
    quats = rng.normal(size=(4, 4))
    quats /= np.linalg.norm(quats, axis=1, keepdims=True)
    quats[2] = -quats[1] * 0.999 + 0.001  # nearly opposite neighbours: the shorter way round
    quats[2] /= np.linalg.norm(quats[2])
    curves = [
        Curve(times, quats, LINEAR, rotation=True),
        Curve(times, rng.normal(size=(4, 3)), LINEAR),
        Curve(times[:1], rng.normal(size=(1, 3)), LINEAR),  # one key: its value at every time
    ]
    t = np.r_[rng.uniform(-0.5, 2.2, 50), times]  # before, inside, after and on the keys
    for curve in curves:
        width = curve.values.shape[1]
        column = np.full((80, width), 7.0)
        rows = rng.permutation(80)[: len(t)]
        write_sampled(curve, t, rows, column)
        assert np.allclose(column[rows], curve.sample(t), atol=1e-12)
        untouched = np.setdiff1d(np.arange(80), rows)
        assert (column[untouched] == 7.0).all()
