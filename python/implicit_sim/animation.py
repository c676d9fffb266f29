"""Headless animations of implicit_sim runs (the README's GIFs, scripts/make_animations.py).

Frames are drawn by matplotlib on an Agg canvas (no display, no pyplot): one mplot3d Poly3DCollection of the bodies'
front-facing triangles with Lambert shading, seen by a fixed orthographic camera framed on the scene. ffmpeg
(palettegen/paletteuse) turns the frames into a GIF. The renderer is a pure function of the bodies (a triangle mesh in
the body frame, or the boundary plane of a half-space), their colours and a pose per body per frame: it does not know
where the poses come from (the Python bindings or the runner's trajectory.csv).

Units: lengths in m, times in s, angles in degrees where the name ends in _deg, colours RGB in [0, 1].
"""
import os
import shutil
import subprocess
from dataclasses import dataclass
from fractions import Fraction

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d import proj3d
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

MOVING_COLOURS = [(0.85, 0.33, 0.10), (0.12, 0.47, 0.71), (0.17, 0.63, 0.17), (0.58, 0.40, 0.74),
                  (0.89, 0.65, 0.10), (0.09, 0.65, 0.65)]
FIXED_COLOUR = (0.72, 0.72, 0.74)
FIXED_COLOURS = [FIXED_COLOUR, (0.60, 0.62, 0.66)]  # greys that tell neighbouring fixed bodies apart
PLANE_COLOUR = (0.88, 0.88, 0.86)
BACKGROUND = (1.0, 1.0, 1.0)


class AnimationError(RuntimeError):
    """ffmpeg missing or failing, or a GIF over its size limit."""


@dataclass
class Body:
    """A body to draw: a mesh (vertices (n, 3) in the body frame, m; triangles (m, 3) int), or, with plane_normal
    set, the boundary plane of a half-space through plane_point (both in the body frame; the normal points out of the
    solid)."""
    name: str
    fixed: bool
    vertices: np.ndarray = None
    triangles: np.ndarray = None
    plane_point: np.ndarray = None
    plane_normal: np.ndarray = None
    colour: tuple = None

    @property
    def is_plane(self):
        return self.plane_normal is not None


@dataclass
class Motion:
    """One pose per body per frame: times (F,) s; positions (F, B, 3) m and rotations (F, B, 3, 3), R_WB, of the body
    frames in the world frame."""
    times: np.ndarray
    positions: np.ndarray
    rotations: np.ndarray


@dataclass
class View:
    """The camera and the picture. lower/upper: the world box the camera frames (m); None fits it on the moving bodies
    over the whole run, widened by margin (a fraction of its size) each side; the box's picture fills the fraction
    fill of the image, times zoom. Planes are drawn clipped to plane_box (lower, upper; default the framing box), the
    ones the camera sees from their free side as a checkerboard of tile-wide squares (m; None: plain). speed: playback
    speed over real time, shown in the time label when not 1."""
    elev_deg: float = 25.0
    azim_deg: float = -60.0
    width_px: int = 400
    height_px: int = 300
    lower: np.ndarray = None
    upper: np.ndarray = None
    margin: float = 0.08
    zoom: float = 1.0
    plane_box: tuple = None
    tile: float = None
    fill: float = 0.96
    time_label: bool = True
    speed: float = 1.0
    ambient: float = 0.35
    dpi: int = 100


def direction(elev_deg, azim_deg):
    """Unit vector at elevation elev_deg above the xy plane and azimuth azim_deg from +x (the mplot3d convention)."""
    e, a = np.radians(elev_deg), np.radians(azim_deg)
    return np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])


def quaternion_matrix(q):
    """Rotation matrices (..., 3, 3) of unit quaternions (..., 4) given as (w, x, y, z)."""
    q = np.asarray(q, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = np.moveaxis(q, -1, 0)
    rows = [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


def superellipsoid_mesh(semi_axes, exponent=2.0, resolution=24):
    """Surface of |x/a|^p + |y/b|^p + |z/c|^p <= 1 (p = 2: an ellipsoid; a = b = c: a sphere) as a latitude-longitude
    mesh: vertices (n, 3) m, triangles (m, 3). resolution: segments around the equator (half as many pole to pole)."""
    a, b, c = semi_axes
    e = 2.0 / exponent
    lat = np.linspace(-np.pi / 2, np.pi / 2, resolution // 2 + 1)
    lon = np.linspace(-np.pi, np.pi, resolution, endpoint=False)
    la, lo = np.meshgrid(lat, lon, indexing="ij")

    def signed_power(v):
        return np.sign(v) * np.abs(v) ** e

    x = a * signed_power(np.cos(la)) * signed_power(np.cos(lo))
    y = b * signed_power(np.cos(la)) * signed_power(np.sin(lo))
    z = c * signed_power(np.sin(la))
    vertices = np.stack([x, y, z], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(len(lat) - 1), np.arange(len(lon)), indexing="ij")
    v00 = i * len(lon) + j
    v01 = i * len(lon) + (j + 1) % len(lon)
    v10, v11 = v00 + len(lon), v01 + len(lon)
    triangles = np.concatenate([np.stack([v00, v01, v11], -1).reshape(-1, 3),
                                np.stack([v00, v11, v10], -1).reshape(-1, 3)])
    return vertices, triangles


def outward_triangles(vertices, triangles):
    """The triangles of a convex mesh wound outward (normals away from its centroid), degenerate ones dropped, and
    their unit normals (body frame)."""
    tri = vertices[triangles]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area2 = np.linalg.norm(normals, axis=1)
    keep = area2 > 1e-12 * max(1.0, float(np.max(area2, initial=0.0)))
    triangles, normals, tri = triangles[keep], normals[keep] / area2[keep, None], tri[keep]
    inward = np.einsum("ij,ij->i", normals, tri.mean(axis=1) - vertices.mean(axis=0)) < 0
    triangles = np.where(inward[:, None], triangles[:, ::-1], triangles)
    normals = np.where(inward[:, None], -normals, normals)
    return triangles, normals


def fit_box(bodies, motion, margin):
    """World box (lower, upper, m) around every moving mesh body at every frame, widened by margin * its size."""
    lower, upper = np.full(3, np.inf), np.full(3, -np.inf)
    for index, body in enumerate(bodies):
        if body.fixed or body.is_plane or body.vertices is None or len(body.vertices) == 0:
            continue
        radius = np.max(np.linalg.norm(body.vertices, axis=1))
        centres = motion.positions[:, index]
        lower = np.minimum(lower, centres.min(axis=0) - radius)
        upper = np.maximum(upper, centres.max(axis=0) + radius)
    if not np.all(np.isfinite(lower)):
        raise AnimationError("no moving body with a shape to frame: give View.lower and View.upper")
    pad = margin * np.max(upper - lower)
    return lower - pad, upper + pad


def plane_polygon(point, normal, lower, upper):
    """The polygon (k, 3), k in 3..6, where the plane through point (m) with the given normal cuts the box
    [lower, upper]; None when it misses the box."""
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    d = float(n @ point)
    corners = np.array([[(lower, upper)[(k >> axis) & 1][axis] for axis in range(3)] for k in range(8)])
    side = corners @ n - d
    tolerance = 1e-9 * max(1.0, float(np.max(np.asarray(upper) - lower)))  # corners this close are on the plane
    points = [corners[k] for k in range(8) if abs(side[k]) <= tolerance]
    for k in range(8):
        for axis in range(3):
            m = k | (1 << axis)
            if m != k and min(side[k], side[m]) < -tolerance and max(side[k], side[m]) > tolerance:
                s = side[k] / (side[k] - side[m])
                points.append(corners[k] + s * (corners[m] - corners[k]))
    if len(points) < 3:
        return None
    points = np.array(points)
    centre = points.mean(axis=0)
    u = np.cross(n, [1.0, 0, 0] if abs(n[0]) < 0.9 else [0, 1.0, 0])
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    angles = np.arctan2((points - centre) @ v, (points - centre) @ u)
    return points[np.argsort(angles)]


def clip_polygon(polygon, normal, offset):
    """The part of a convex polygon (k, 3) where normal . x <= offset (Sutherland-Hodgman), (j, 3); maybe empty."""
    out = []
    for a, b in zip(polygon, np.roll(polygon, -1, axis=0)):
        da, db = normal @ a - offset, normal @ b - offset
        if da <= 0:
            out.append(a)
        if (da < 0 < db) or (db < 0 < da):
            out.append(a + da / (da - db) * (b - a))
    return np.array(out).reshape(-1, 3)


def checker_tiles(polygon, normal, tile):
    """The polygon cut into the squares of a checkerboard of side tile (m) laid in its plane (on the plane's own
    axes): two lists of polygons, the light and the dark squares."""
    n = normal / np.linalg.norm(normal)
    u = np.cross(n, [0, 0, 1.0]) if abs(n[2]) < 0.9 else np.array([1.0, 0, 0])
    u = (u - (u @ n) * n) / np.linalg.norm(u - (u @ n) * n)
    v = np.cross(n, u)
    su, sv = polygon @ u, polygon @ v
    light, dark = [], []
    for i in range(int(np.floor(su.min() / tile)), int(np.ceil(su.max() / tile))):
        strip = clip_polygon(clip_polygon(polygon, -u, -i * tile), u, (i + 1) * tile)
        for j in range(int(np.floor(sv.min() / tile)), int(np.ceil(sv.max() / tile))):
            square = clip_polygon(clip_polygon(strip, -v, -j * tile), v, (j + 1) * tile) if len(strip) else strip
            if len(square) >= 3:
                (light if (i + j) % 2 == 0 else dark).append(square)
    return light, dark


class Renderer:
    """Draws frames of the given bodies through a fixed camera: render(positions, rotations, t) -> RGB image
    (height_px, width_px, 3) uint8; project(points) -> image coordinates of world points."""

    def __init__(self, bodies, view, lower, upper):
        self.bodies, self.view = bodies, view
        self.lower, self.upper = np.asarray(lower, float), np.asarray(upper, float)
        self.plane_box = view.plane_box or (self.lower, self.upper)
        self.eye = direction(view.elev_deg, view.azim_deg)  # from the scene towards the camera
        self.light = direction(view.elev_deg + 35.0, view.azim_deg - 40.0)  # towards the light
        self.meshes = [outward_triangles(b.vertices, b.triangles) if not b.is_plane else None for b in bodies]
        self.figure = Figure(figsize=(view.width_px / view.dpi, view.height_px / view.dpi), dpi=view.dpi,
                             facecolor=BACKGROUND)
        self.canvas = FigureCanvasAgg(self.figure)
        self.axes = self._make_axes()
        self.behind = self._add_layer(1)  # planes the camera sees from their free side: they hide nothing
        self.solids = self._add_layer(2)
        self.in_front = self._add_layer(3)  # planes seen from inside the solid: see-through
        self.label = self.figure.text(0.02, 0.97, "", fontsize=9, va="top", family="monospace",
                                      bbox=dict(facecolor=BACKGROUND, alpha=0.8, edgecolor="none", pad=1.5))
        self.canvas.draw()

    def _make_axes(self):
        """The 3D axes: orthographic, one scale on x, y, z, the framing box centred and filling view.fill."""
        axes = self.figure.add_axes([0, 0, 1, 1], projection="3d", facecolor=BACKGROUND)
        axes.set_proj_type("ortho")
        axes.view_init(elev=self.view.elev_deg, azim=self.view.azim_deg)
        for setter, lo, hi in zip((axes.set_xlim, axes.set_ylim, axes.set_zlim), self.lower, self.upper):
            setter(lo, hi)
        axes.set_box_aspect(self.upper - self.lower)  # one scale on all three axes
        axes.set_axis_off()
        axes.computed_zorder = False
        self.axes = axes
        corners = np.array([[(self.lower, self.upper)[(k >> i) & 1][i] for i in range(3)] for k in range(8)])
        self.canvas.draw()  # lays the axes out: the projection is final only after a draw
        extent = np.ptp(self.project(corners), axis=0)  # the box's picture at zoom 1 (px)
        zoom = self.view.fill * min(self.view.width_px / extent[0], self.view.height_px / extent[1])
        axes.set_box_aspect(self.upper - self.lower, zoom=zoom * self.view.zoom)
        self.canvas.draw()
        picture = self.project(corners)
        offset = (picture.min(axis=0) + picture.max(axis=0)) / 2 - [self.view.width_px / 2, self.view.height_px / 2]
        axes.set_position([-offset[0] / self.view.width_px, offset[1] / self.view.height_px, 1, 1])  # centred
        return axes

    def _add_layer(self, zorder):
        layer = Poly3DCollection([], zorder=zorder, linewidths=0.4, antialiaseds=True)
        layer.set_clip_on(False)  # mplot3d's axes is a square inside the figure: draw over all of it
        self.axes.add_collection3d(layer)
        return layer

    def shade(self, colour, normals):
        """Lambert: colour * (ambient + (1 - ambient) * max(0, n . light)), RGBA rows."""
        lit = self.view.ambient + (1 - self.view.ambient) * np.clip(normals @ self.light, 0.0, 1.0)
        rgb = np.clip(np.outer(lit, colour), 0.0, 1.0)
        return np.column_stack([rgb, np.ones(len(rgb))])

    def render(self, positions, rotations, t=None):
        """One frame: positions (B, 3) m and rotations (B, 3, 3) of the bodies, t the time label (s) or None."""
        solid_faces, solid_colours, planes = [], [], ([], [], [], [])
        for body, mesh, p, R in zip(self.bodies, self.meshes, positions, rotations):
            colour = body.colour or (FIXED_COLOUR if body.fixed else MOVING_COLOURS[0])
            if body.is_plane:
                self._plane(body, colour, p, R, planes)
            elif mesh is not None and len(mesh[0]):
                triangles, normals = mesh
                normals = normals @ R.T
                world = body.vertices @ R.T + p
                visible = (normals @ self.eye > 0) & self.in_picture(world, triangles)  # back faces are hidden
                solid_faces.append(world[triangles[visible]])
                solid_colours.append(self.shade(colour, normals[visible]))
        faces = np.concatenate(solid_faces) if solid_faces else np.zeros((0, 3, 3))
        colours = np.concatenate(solid_colours) if solid_colours else np.zeros((0, 4))
        self._fill(self.solids, faces, colours, colours)
        self._fill(self.behind, planes[0], planes[1], planes[1])
        self._fill(self.in_front, planes[2], planes[3], [(0.3, 0.3, 0.3, 0.6)] * len(planes[2]))
        speed = f"  ({self.view.speed:g}x)" if self.view.speed != 1 else ""
        self.label.set_text(f"t = {t:.2f} s{speed}" if t is not None else "")
        self.label.set_visible(t is not None and self.view.time_label)
        self.canvas.draw()
        return np.asarray(self.canvas.buffer_rgba())[:, :, :3].copy()

    def _plane(self, body, colour, p, R, planes):
        normal = R @ body.plane_normal
        point = R @ (body.plane_point if body.plane_point is not None else np.zeros(3)) + p
        polygon = plane_polygon(point, normal, *self.plane_box)
        if polygon is None:
            return
        rgba = self.shade(colour, normal[None, :])[0]
        if normal @ self.eye >= 0:
            light, dark = checker_tiles(polygon, normal, self.view.tile) if self.view.tile else ([polygon], [])
            planes[0].extend(light + dark)
            planes[1].extend([rgba] * len(light) + [(*(0.9 * rgba[:3]), 1.0)] * len(dark))
        else:
            planes[2].append(polygon)
            planes[3].append((*rgba[:3], 0.12))

    @staticmethod
    def _fill(layer, faces, facecolours, edgecolours):
        layer.set_verts(list(faces))
        layer.set_facecolor(facecolours if len(faces) else "none")
        layer.set_edgecolor(edgecolours if len(faces) else "none")

    def in_picture(self, vertices, triangles):
        """Per triangle: False when all three corners are beyond the same edge of the picture."""
        xy = self.project(vertices)[triangles]  # (m, 3, 2) px
        size = np.array([self.view.width_px, self.view.height_px])
        return ~(np.all(xy < 0, axis=1).any(axis=1) | np.all(xy > size, axis=1).any(axis=1))

    def project(self, points):
        """Image coordinates (n, 2) of world points (n, 3), m: x to the right, y down, from the image's top-left
        corner, in pixels (the centre of pixel (row i, column j) is (j + 0.5, i + 0.5))."""
        points = np.atleast_2d(points)
        x, y, _ = proj3d.proj_transform(points[:, 0], points[:, 1], points[:, 2], self.axes.get_proj())
        display = self.axes.transData.transform(np.column_stack([x, y]))
        return np.column_stack([display[:, 0], self.view.height_px - display[:, 1]])


def frames(bodies, motion, view):
    """The rendered frames (a generator of RGB images), camera framed by view (fit_box when view.lower is None)."""
    if view.lower is None:
        lower, upper = fit_box(bodies, motion, view.margin)
    else:
        lower, upper = view.lower, view.upper
    renderer = Renderer(bodies, view, lower, upper)
    for k, t in enumerate(motion.times):
        yield renderer.render(motion.positions[k], motion.rotations[k], t)


def ffmpeg_path():
    path = shutil.which("ffmpeg")
    if path is None:
        raise AnimationError("ffmpeg not found on PATH: it assembles the GIF (Debian: apt-get install ffmpeg)")
    return path


def write_gif(images, path, fps, max_colours=128, final_delay_s=1.0, max_bytes=None):
    """Pipes RGB images (an iterable of equal-size (h, w, 3) uint8 arrays) into ffmpeg, which writes the GIF at path
    with one palette for the whole clip (palettegen, paletteuse with ordered dither; only the changed rectangle of
    each frame is stored). fps: frames per second of playback (at most 50: GIF delays are centiseconds); the last
    frame stays final_delay_s. Returns (frames written, bytes); raises AnimationError when ffmpeg fails or the file
    exceeds max_bytes."""
    if not 0 < fps <= 50:
        raise AnimationError(f"fps must be in (0, 50], got {fps}")
    rate = Fraction(fps).limit_denominator(1000)
    graph = (f"[0:v]split[a][b];[a]palettegen=max_colors={max_colours}:stats_mode=full[p];"
             "[b][p]paletteuse=dither=bayer:bayer_scale=3:diff_mode=rectangle")
    process, count = None, 0
    try:
        for image in images:
            if process is None:
                height, width = image.shape[:2]
                command = [ffmpeg_path(), "-y", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt", "rgb24",
                           "-s", f"{width}x{height}", "-framerate", str(rate), "-i", "-",
                           "-filter_complex", graph, "-loop", "0", "-final_delay", str(round(100 * final_delay_s)),
                           "-f", "gif", str(path)]
                process = subprocess.Popen(command, stdin=subprocess.PIPE, stderr=subprocess.PIPE)
            process.stdin.write(np.ascontiguousarray(image, dtype=np.uint8).tobytes())
            count += 1
    finally:
        if process is not None:
            process.stdin.close()
            error = process.stderr.read().decode(errors="replace")
            process.wait()
    if process is None:
        raise AnimationError("no frames to write")
    if process.returncode != 0:
        raise AnimationError(f"ffmpeg failed (exit {process.returncode}) writing {path}: {error.strip()}")
    size = os.path.getsize(path)
    if max_bytes is not None and size > max_bytes:
        raise AnimationError(f"{path} is {size} bytes, over the limit of {max_bytes} bytes")
    return count, size


def animate(bodies, motion, view, path, fps, max_bytes=None):
    """Renders every frame of motion and writes the GIF: returns (frames, bytes)."""
    return write_gif(frames(bodies, motion, view), path, fps, max_bytes=max_bytes)
