"""The animation pipeline (python/implicit_sim/animation.py, scripts/make_animations.py): a tiny P3 GIF made by the
script itself, and the renderer's geometry (projection, Lambert shading, planes) against what it draws."""
import pathlib
import subprocess
import sys

import numpy as np
import pytest

from implicit_sim import animation

REPO = pathlib.Path(__file__).resolve().parents[2]
RED = (1.0, 0.0, 0.0)


def gif_frames(path):
    """Frames in a GIF, counted by ffprobe decoding it."""
    out = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
                          "stream=nb_read_frames", "-of", "csv=p=0", str(path)],
                         check=True, capture_output=True, text=True).stdout
    return int(out.strip())


def test_make_animations_writes_a_small_valid_gif_of_p3(tmp_path):
    # 10 steps of P3 (0.1 s at h = 0.01), 4 frames, 160 px wide: the script's own code path, bindings included.
    result = subprocess.run([sys.executable, str(REPO / "scripts" / "make_animations.py"), str(tmp_path), "--only",
                             "p3", "--duration", "0.1", "--frames", "4", "--width", "160"],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "10 steps of 0.01 s (all converged)" in result.stdout, result.stdout
    gif = tmp_path / "p3.gif"
    assert gif.read_bytes()[:6] in (b"GIF89a", b"GIF87a")
    assert gif_frames(gif) == 4
    assert 0 < gif.stat().st_size < 2_000_000
    width, height = subprocess.run(["ffprobe", "-v", "error", "-show_entries", "stream=width,height", "-of",
                                    "csv=p=0", str(gif)], check=True, capture_output=True, text=True
                                   ).stdout.strip().split(",")
    assert (int(width), int(height)) == (160, 120)


def test_make_animations_refuses_bad_arguments(tmp_path):
    result = subprocess.run([sys.executable, str(REPO / "scripts" / "make_animations.py"), str(tmp_path), "--only",
                             "nope"], capture_output=True, text=True, timeout=60)
    assert result.returncode == 2 and "nope" in result.stderr


def sphere_renderer(centre, radius, elev_deg=30.0, azim_deg=-50.0):
    """A renderer of one red sphere (moving) framed by the unit box, and the sphere's pose."""
    vertices, triangles = animation.superellipsoid_mesh((radius,) * 3, 2.0, 32)
    body = animation.Body("ball", False, vertices, triangles, colour=RED)
    view = animation.View(elev_deg=elev_deg, azim_deg=azim_deg, width_px=200, height_px=160, time_label=False)
    renderer = animation.Renderer([body], view, np.zeros(3), np.ones(3))
    return renderer, np.array([centre]), np.eye(3)[None]


@pytest.mark.parametrize("centre", [(0.5, 0.5, 0.5), (0.8, 0.2, 0.7), (0.1, 0.9, 0.3)])
def test_the_sphere_is_drawn_where_project_puts_its_centre(centre):
    radius = 0.06
    renderer, positions, rotations = sphere_renderer(centre, radius)
    image = renderer.render(positions, rotations).astype(int)
    red = (image[:, :, 0] > 100) & (image[:, :, 1] < 60) & (image[:, :, 2] < 60)
    rows, cols = np.nonzero(red)
    assert len(rows) > 20
    drawn = np.array([cols.mean() + 0.5, rows.mean() + 0.5])  # pixel centres, as project() counts
    expected = renderer.project(np.array(centre))[0]
    assert np.linalg.norm(drawn - expected) < 1.0, (drawn, expected)
    # Orthographic: the disc's radius in px is the radius in m times the scale, the same everywhere in the picture.
    side = np.cross(renderer.eye, [0, 0, 1.0])
    side /= np.linalg.norm(side)
    scale = np.linalg.norm(renderer.project(np.array(centre) + side) - expected)  # px per m
    assert np.sqrt(red.sum() / np.pi) == pytest.approx(radius * scale, rel=0.06)


def test_the_framing_box_is_centred_and_fills_the_picture():
    renderer, _, _ = sphere_renderer((0.5, 0.5, 0.5), 0.05)
    corners = np.array([[(k >> i) & 1 for i in range(3)] for k in range(8)], dtype=float)
    picture = renderer.project(corners)
    centre = (picture.min(axis=0) + picture.max(axis=0)) / 2
    assert np.allclose(centre, [100, 80], atol=0.5)
    extent = np.ptp(picture, axis=0) / [200, 160]
    assert max(extent) == pytest.approx(renderer.view.fill, abs=0.01) and min(extent) <= renderer.view.fill + 0.01


def test_lambert_shading():
    renderer, _, _ = sphere_renderer((0.5, 0.5, 0.5), 0.05)
    ambient = renderer.view.ambient
    normals = np.array([renderer.light, -renderer.light, np.cross(renderer.light, [0, 0, 1.0])])
    normals[2] /= np.linalg.norm(normals[2])
    shaded = renderer.shade((0.5, 1.0, 0.2), normals)
    assert np.allclose(shaded[0], [0.5, 1.0, 0.2, 1.0])  # facing the light: the full colour
    assert np.allclose(shaded[1, :3], ambient * np.array([0.5, 1.0, 0.2]))  # facing away: ambient only
    assert np.allclose(shaded[2, :3], ambient * np.array([0.5, 1.0, 0.2]))  # grazing


def test_a_plane_is_cut_by_the_box_and_tiled_without_gaps():
    square = animation.plane_polygon(np.array([0, 0, 0.25]), np.array([0, 0, 1.0]), np.zeros(3), np.ones(3))
    assert len(square) == 4 and np.allclose(square[:, 2], 0.25)
    assert sorted(map(tuple, square[:, :2].round(12))) == [(0, 0), (0, 1), (1, 0), (1, 1)]
    hexagon = animation.plane_polygon(np.full(3, 0.5), np.ones(3), np.zeros(3), np.ones(3))
    assert len(hexagon) == 6
    assert animation.plane_polygon(np.full(3, 2.0), np.ones(3), np.zeros(3), np.ones(3)) is None

    def area(polygon):
        return 0.5 * np.linalg.norm(sum(np.cross(a, b) for a, b in zip(polygon, np.roll(polygon, -1, axis=0))))

    light, dark = animation.checker_tiles(hexagon, np.ones(3), 0.13)
    assert len(light) > 5 and len(dark) > 5
    assert sum(map(area, light + dark)) == pytest.approx(area(hexagon), rel=1e-9)


def test_write_gif_says_when_ffmpeg_is_missing(tmp_path, monkeypatch):
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(animation.AnimationError, match="ffmpeg not found"):
        animation.write_gif([np.zeros((8, 8, 3), np.uint8)], tmp_path / "x.gif", 10)


def test_write_gif_enforces_the_size_limit(tmp_path):
    noise = np.random.default_rng(1).integers(0, 255, (6, 64, 64, 3), dtype=np.uint8)
    with pytest.raises(animation.AnimationError, match="over the limit"):
        animation.write_gif(noise, tmp_path / "noise.gif", 10, max_bytes=1000)
    assert gif_frames(tmp_path / "noise.gif") == 6
