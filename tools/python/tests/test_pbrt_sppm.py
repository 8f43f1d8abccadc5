"""Tests of the Python package against analytic answers and against the command line
(`PBRT_SPPM_BIN` names the pbrt-sppm binary; `cargo test` sets it)."""

import json
import os
import pathlib
import signal
import subprocess
import threading
import time

import numpy as np
import pytest

import pbrt_sppm

ROOT = pathlib.Path(__file__).resolve().parents[3]
CORNELL = ROOT / "pbrt-scenes/v3/cornell-glass.pbrt"
BIN = os.environ.get("PBRT_SPPM_BIN")
needs_bin = pytest.mark.skipif(not BIN, reason="PBRT_SPPM_BIN does not name the pbrt-sppm binary")

# A unit sphere at the origin, lit by a quad area light and a point light, seen by a
# camera on -z: small and fast, with known ray hits.
SPHERE = """
LookAt 0 0 -5  0 0 0  0 1 0
Camera "perspective" "float fov" [30]
Film "image" "integer xresolution" [24] "integer yresolution" [16] "string filename" "unused.exr"
Sampler "halton" "integer pixelsamples" [4]
Integrator "sppm" "integer numiterations" [4] "integer photonsperiteration" [2000]
WorldBegin
LightSource "point" "point from" [2 2 -3] "rgb I" [4 4 4]
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [3 3 3]
  Translate 0 3 0
  Rotate 90 1 0 0
  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
    "point P" [-1 -1 0  1 -1 0  1 1 0  -1 1 0]
AttributeEnd
Material "matte" "rgb Kd" [0.6 0.5 0.4]
Shape "sphere" "float radius" [1]
WorldEnd
"""


def cli(*args, **kw):
    return subprocess.run([BIN, *map(str, args)], capture_output=True, text=True, **kw)


def test_load_reads_text_paths_and_path_likes_alike(tmp_path):
    f = tmp_path / "sphere.pbrt"
    f.write_text(SPHERE)
    for source in [SPHERE, str(f), f]:
        s = pbrt_sppm.load(source)
        assert s.size == (24, 16)
        assert s.check()["counts"]["sphere"] == 1


def test_errors_carry_file_line_and_column(tmp_path):
    bad = SPHERE.replace('"float radius" [1]', '"float radius" [-1]')
    with pytest.raises(pbrt_sppm.SceneError) as e:
        pbrt_sppm.load(bad)
    line = bad.splitlines().index('Shape "sphere" "float radius" [-1]') + 1
    assert (e.value.file, e.value.line) == ("<string>", line)
    assert e.value.column == len('Shape "sphere" "float radius" ') + 1  # at the value's [
    assert str(e.value).startswith(f"<string>:{line}:{e.value.column}: error: ")
    # An error in an included file names that file.
    (tmp_path / "inc.pbrt").write_text('Shape "sphere" "float radius" "oops"\n')
    (tmp_path / "main.pbrt").write_text(SPHERE.replace("WorldEnd", 'Include "inc.pbrt"\nWorldEnd'))
    with pytest.raises(pbrt_sppm.SceneError) as e:
        pbrt_sppm.load(tmp_path / "main.pbrt")
    assert e.value.file.endswith("inc.pbrt") and e.value.line == 1
    with pytest.raises(pbrt_sppm.SceneError) as e:
        pbrt_sppm.load(tmp_path / "missing.pbrt")
    assert e.value.line is None and "missing.pbrt" in e.value.file


def test_syntax_and_fix_options_are_the_command_lines():
    assert pbrt_sppm.load(SPHERE, syntax="v4").check()["syntax"] == "v4"
    with pytest.raises(ValueError):
        pbrt_sppm.load(SPHERE, syntax="v5")
    with pytest.raises(ValueError):
        pbrt_sppm.load(SPHERE, fix="no-such-fix")
    with pytest.raises(pbrt_sppm.SceneError):
        pbrt_sppm.load(SPHERE, limits={"pixels": 100})


def test_colour_chooses_what_paths_carry():
    # SPHERE is a pbrt-v3 file: RGB by default, spectral when asked; a bad name says so.
    assert pbrt_sppm.load(SPHERE).check()["colour"] == "rgb"
    assert pbrt_sppm.load(SPHERE, colour="spectral").check()["colour"] == "spectral"
    with pytest.raises(ValueError, match="colour: expected"):
        pbrt_sppm.load(SPHERE, colour="grey")


@needs_bin
def test_check_is_check_json(tmp_path):
    f = tmp_path / "sphere.pbrt"
    f.write_text(SPHERE)
    # A fixed memory limit: by default it is the memory free at each load, which moves.
    out = cli("check", "--json", "--shapes", "--limit", "memory=8e9", f)
    assert out.returncode == 0, out.stderr
    got = pbrt_sppm.load(f, limits={"memory": "8e9"}).check(shapes=True)
    assert got == json.loads(out.stdout)
    assert got["memory"]["limit_bytes"] == 8_000_000_000 and not got["memory"]["limit_is_free_memory"]


def test_trace_answers_as_the_geometry_says():
    s = pbrt_sppm.load(SPHERE)
    o = np.array([[0, 0, -5], [0, 0, -5], [0, 0, -5], [0.5, 0, -5]], dtype=np.float32)
    d = np.array([[0, 0, 1], [0, 0, 2], [0, 1, 0], [0, 0, 1]], dtype=np.float32)
    r = s.trace(o, d)
    assert list(r["hit"]) == [True, True, False, True]
    assert r["t"][0] == pytest.approx(4.0, abs=1e-5) and r["t"][1] == pytest.approx(2.0, abs=1e-5)
    np.testing.assert_allclose(r["p"][0], [0, 0, -1], atol=1e-5)
    np.testing.assert_allclose(r["n"][0], [0, 0, -1], atol=1e-5)
    z = -np.sqrt(1 - 0.25)
    np.testing.assert_allclose(r["p"][3], [0.5, 0, z], atol=1e-5)
    assert list(r["shape"]) == ["sphere", "sphere", "", "sphere"]
    assert np.isnan(r["t"][2]) and np.isnan(r["p"][2]).all() and r["shape_index"][2] == -1
    assert r["triangle"][0] == -1
    # tmax short of the sphere: a miss.
    assert not s.trace(o[:1], d[:1], tmax=[3.9])["hit"][0]
    with pytest.raises(ValueError, match="ray 0"):
        s.trace([[0, 0, 0]], [[0, 0, 0]])
    with pytest.raises(ValueError):
        s.trace(o, d[:2])


@needs_bin
def test_trace_matches_the_trace_command(tmp_path):
    f = tmp_path / "sphere.pbrt"
    f.write_text(SPHERE)
    rng = np.random.default_rng(7)
    o = np.tile([0.0, 0.0, -5.0], (200, 1)).astype(np.float32)
    d = (rng.normal(size=(200, 3)) * [0.3, 0.3, 0.1] + [0, 0, 1]).astype(np.float32)
    lines = "\n".join(" ".join(f"{v:.9g}" for v in np.concatenate([a, b])) for a, b in zip(o, d))
    out = cli("trace", f, input=lines)
    assert out.returncode == 0, out.stderr
    theirs = [json.loads(x) for x in out.stdout.splitlines()]
    ours = pbrt_sppm.load(f).trace(o, d)
    assert sum(t["hit"] for t in theirs) > 20
    for i, t in enumerate(theirs):
        assert ours["hit"][i] == t["hit"]
        if t["hit"]:
            assert ours["t"][i] == pytest.approx(t["t"], rel=1e-6)
            np.testing.assert_allclose(ours["n"][i], t["n"], rtol=1e-6, atol=1e-7)
            assert (ours["shape"][i], ours["shape_index"][i]) == (t["shape"], t["shape_index"])
            if "triangle" in t:
                assert ours["triangle"][i] == t["triangle"]


@needs_bin
def test_render_is_the_command_lines_image(tmp_path):
    out_exr = tmp_path / "cli.exr"
    r = cli(CORNELL, "--spp", 3, "--seed", 5, "--integrator", "vcm", "--quiet", "--outfile", out_exr)
    assert r.returncode == 0, r.stderr
    theirs = pbrt_sppm.read_image(out_exr)
    ours = pbrt_sppm.load(CORNELL).render(spp=3, seed=5, integrator="vcm", threads=1)
    assert ours.dtype == np.float32 and ours.shape == theirs.shape
    # Deterministic for any thread count: the same bits as the command line's.
    np.testing.assert_array_equal(ours, theirs)


@needs_bin
def test_read_buckets_reads_a_spectral_films_buckets(tmp_path):
    # The command line renders a pbrt-v4 spectral film: R, G, B and 4 buckets over
    # 400-700 nm; an RGB image has none.
    scene = tmp_path / "s.pbrt"
    scene.write_text(
        'LookAt 0 0 -5 0 0 0 0 1 0 Camera "perspective" Film "spectral" "integer xresolution" 6 "integer yresolution" 4 '
        '"integer nbuckets" 4 "float lambdamin" 400 "float lambdamax" 700 Integrator "path" '
        'WorldBegin LightSource "infinite" "blackbody L" 5000 Material "diffuse" Shape "sphere"'
    )
    out = tmp_path / "s.exr"
    r = cli("render", scene, "--spp", 8, "--quiet", "--outfile", out)
    assert r.returncode == 0, r.stderr
    b = pbrt_sppm.read_buckets(out)
    np.testing.assert_allclose(b["wavelengths"], [437.5, 512.5, 587.5, 662.5])
    assert b["names"][0] == "S0.437,500nm" and b["values"].shape == (4, 6, 4)
    assert b["values"].min() >= 0 and b["values"].max() > 0
    assert pbrt_sppm.read_buckets(ROOT / "tests/data/pbrt-ref/v4-sensor.exr") is None


@needs_bin
def test_volume_gather_is_the_command_lines(tmp_path):
    fog = ROOT / "pbrt-scenes/verify/v4-fog-box.pbrt"
    out_exr = tmp_path / "beams.exr"
    r = cli(fog, "--spp", 2, "--photons", 20000, "--volume-gather", "beams", "--quiet", "--outfile", out_exr)
    assert r.returncode == 0, r.stderr
    s = pbrt_sppm.load(fog)
    beams = s.render(spp=2, photons=20000, volume_gather="beams", threads=1)
    np.testing.assert_array_equal(beams, pbrt_sppm.read_image(out_exr))
    assert not np.array_equal(beams, s.render(spp=2, photons=20000, volume_gather="points"))
    with pytest.raises(ValueError, match="volume_gather"):
        s.render(spp=1, volume_gather="rays")
    with pytest.raises(ValueError, match="SPPM"):
        s.render(spp=1, volume_gather="beams", integrator="vcm")


def test_render_options_and_progress():
    s = pbrt_sppm.load(SPHERE)
    seen = []
    a = s.render(spp=3, seed=2, progress=lambda done, planned, t: seen.append((done, planned, t)))
    assert a.shape == (16, 24, 3) and a.dtype == np.float32
    assert [x[:2] for x in seen] == [(1, 3), (2, 3), (3, 3)]
    assert all(s0 <= s1 for (_, _, s0), (_, _, s1) in zip(seen, seen[1:]))
    assert a.mean() > 0.01
    np.testing.assert_array_equal(a, s.render(spp=3, seed=2))
    assert not np.array_equal(a, s.render(spp=3, seed=3))
    assert s.last_render["iterations"] == 3 and s.last_render["integrator"] == "sppm"
    assert s.render(spp=2, photons=10, integrator="bdpt").shape == (16, 24, 3)
    assert s.last_render["integrator"] == "bdpt" and s.last_render["photons"] == 20
    with pytest.raises(ValueError, match="integrator"):
        s.render(integrator="path")
    with pytest.raises(ValueError):
        s.render(spp=0)
    with pytest.raises(TypeError, match="unknown options"):
        s.render(spp=1, colour="red")


def test_a_progress_callback_can_stop_the_render_or_raise():
    s = pbrt_sppm.load(SPHERE)
    s.render(spp=50, progress=lambda done, planned, t: done < 2)
    assert s.last_render["iterations"] == 2 and s.last_render["interrupted"]

    def fail(done, planned, t):
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        s.render(spp=50, progress=fail)


def test_ctrl_c_stops_the_render_and_raises_keyboard_interrupt():
    s = pbrt_sppm.load(SPHERE)
    iterations = []
    # A real SIGINT from outside, as Ctrl-C sends, with Python's own handler in place:
    # a process started in the background by a shell without job control (a CI script)
    # inherits SIGINT ignored, and then neither Ctrl-C nor this signal reaches Python.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    start = time.monotonic()
    try:
        with pytest.raises(KeyboardInterrupt):
            killer = subprocess.Popen(["sh", "-c", f"sleep 1; kill -INT {os.getpid()}"])
            s.render(spp=1_000_000, photons=20000, progress=lambda d, p, t: iterations.append(d))
        killer.wait()
    finally:
        signal.signal(signal.SIGINT, previous)
    assert time.monotonic() - start < 20
    assert 0 < len(iterations) < 1_000_000
    # The scene is still usable after an interrupt.
    assert s.render(spp=1).shape == (16, 24, 3)


def test_the_gil_is_released_while_rendering():
    s = pbrt_sppm.load(SPHERE)
    counts = []
    done = threading.Event()

    def count():
        n = 0
        while not done.is_set():
            n += 1
        counts.append(n)

    t = threading.Thread(target=count)
    t.start()
    try:
        s.render(spp=30, photons=20000, threads=1)
    finally:
        done.set()
        t.join()
    # With the GIL held the counter would run only in the interpreter's switch slices
    # of the render's progress checks; released, it runs the whole time.
    assert counts[0] > 100_000


def test_render_with_errors_measures_against_the_reference():
    s = pbrt_sppm.load(SPHERE)
    ref = s.render(spp=16, seed=9)
    image, errors = s.render_with_errors(ref, spp=4, seed=1)
    assert list(errors["iteration"]) == [1, 2, 3, 4]
    assert list(errors["photons"]) == [2000, 4000, 6000, 8000]
    assert (np.diff(errors["seconds"]) >= 0).all()
    assert errors["relmse"][-1] == pytest.approx(pbrt_sppm.relmse(image, ref), rel=1e-9)
    assert errors["relmse"][-1] < errors["relmse"][0]
    with pytest.raises(RuntimeError, match="reference"):
        s.render_with_errors(np.zeros((5, 5, 3)), spp=1)


def test_image_tools_on_arrays(tmp_path):
    rng = np.random.default_rng(1)
    b = rng.uniform(0.1, 2.0, size=(20, 30, 3)).astype(np.float32)
    a = (b * rng.uniform(0.9, 1.1, size=b.shape)).astype(np.float32)
    d = pbrt_sppm.diff(a, b)
    a64, b64 = a.astype(np.float64), b.astype(np.float64)
    assert d["mse"] == pytest.approx(((a64 - b64) ** 2).mean(), rel=1e-9)
    assert d["relmse"] == pytest.approx(((a64 - b64) ** 2 / (b64**2 + 0.01)).mean(), rel=1e-9)
    assert d["max_abs"] == pytest.approx(np.abs(a64 - b64).max(), rel=1e-9)
    assert pbrt_sppm.relmse(b, b) == 0.0
    # One tile 10% bright: tiles finds it, its place and its mean.
    c = b.copy()
    c[0:5, 22:30, 1] *= 1.1
    t = pbrt_sppm.tiles(c, b, grid=4)
    assert t["at"] == "tile (3, 0)" and t["channel"] == "G"
    assert t["worst"] == pytest.approx(0.1, rel=1e-4)
    np.testing.assert_allclose(t["reference_tile_means"][0, 3], b[0:5, 22:30].mean(axis=(0, 1)), rtol=1e-6)
    np.testing.assert_allclose(t["image_means"], c.reshape(-1, 3).mean(axis=0), rtol=1e-6)
    with pytest.raises(ValueError):
        pbrt_sppm.diff(a, b[:, :10])
    with pytest.raises(ValueError):
        pbrt_sppm.tiles(a, b, grid=0)
    # EXR round trip is exact; PNG is 8-bit sRGB.
    pbrt_sppm.write_image(tmp_path / "a.exr", a)
    np.testing.assert_array_equal(pbrt_sppm.read_image(tmp_path / "a.exr"), a)
    pbrt_sppm.write_image(tmp_path / "a.png", np.clip(a, 0, 1))
    np.testing.assert_allclose(pbrt_sppm.read_image(tmp_path / "a.png"), np.clip(a, 0, 1), atol=0.02)
    with pytest.raises(OSError):
        pbrt_sppm.write_image(tmp_path / "a.tiff", a)
    with pytest.raises(OSError):
        pbrt_sppm.read_image(tmp_path / "none.exr")
