"""The look of a rendered face: camera, lights and materials from ``look.json``.

The browser viewer bundles the same ``look.json`` and ``shaders/shade.glsl``, so the offscreen
renderer and the viewer frame, light and shade a face the same way.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from functools import cache
from importlib import resources
from typing import Any

import numpy as np

from emogen.appearance.params import Appearance
from emogen.errors import ConfigError
from emogen.model.face import FaceModel


@dataclass(frozen=True)
class Camera:
    """A perspective camera (OpenGL conventions, y up, looking from ``position`` at ``target``)."""

    position: tuple[float, float, float]
    target: tuple[float, float, float]
    up: tuple[float, float, float]
    fov_y_deg: float
    near: float
    far: float

    def view_matrix(self) -> np.ndarray:
        """(4, 4) world → camera."""
        eye, target, up = (
            np.asarray(x, dtype=np.float64) for x in (self.position, self.target, self.up)
        )
        f = target - eye
        f /= np.linalg.norm(f)
        s = np.cross(f, up)
        s /= np.linalg.norm(s)
        u = np.cross(s, f)
        m = np.eye(4)
        m[0, :3], m[1, :3], m[2, :3] = s, u, -f
        m[:3, 3] = -m[:3, :3] @ eye
        return m

    def projection_matrix(self, aspect: float = 1.0) -> np.ndarray:
        """(4, 4) camera → clip (like three.js's PerspectiveCamera)."""
        t = 1.0 / np.tan(np.radians(self.fov_y_deg) / 2)
        n, f = self.near, self.far
        m = np.zeros((4, 4))
        m[0, 0], m[1, 1] = t / aspect, t
        m[2, 2], m[2, 3] = -(f + n) / (f - n), -2 * f * n / (f - n)
        m[3, 2] = -1.0
        return m

    def fitted(
        self, top_y: float, bottom_y: float, depth_z: float, fill: float, top: float
    ) -> Camera:
        """This camera moved vertically and zoomed so that the span from ``bottom_y`` to
        ``top_y`` (cm, at depth ``depth_z``) fills ``fill`` of the image height, its top edge
        ``top`` of the height below the image's top (looking along −z, as the look's cameras)."""
        distance = self.position[2] - depth_z
        height = (top_y - bottom_y) / fill
        centre = top_y + top * height - height / 2
        fov = float(np.degrees(2 * np.arctan(height / 2 / distance)))
        return replace(
            self,
            position=(self.position[0], centre, self.position[2]),
            target=(self.target[0], centre, self.target[2]),
            fov_y_deg=fov,
        )

    def project(self, points: np.ndarray, size: int) -> np.ndarray:
        """Pixel coordinates (n, 2) — x right, y down, top-left pixel's centre at (0.5, 0.5) —
        of points (n, 3) in cm in a ``size``×``size`` image."""
        p = np.c_[np.asarray(points, dtype=np.float64).reshape(-1, 3), np.ones(len(points))]
        clip = p @ (self.projection_matrix(1.0) @ self.view_matrix()).T
        ndc = clip[:, :2] / clip[:, 3:4]
        return np.c_[(ndc[:, 0] + 1) / 2 * size, (1 - ndc[:, 1]) / 2 * size]


@dataclass(frozen=True)
class Part:
    """A shading part: the regions it covers and its material."""

    name: str
    regions: tuple[str, ...]
    albedo_srgb: tuple[float, float, float]
    specular: float
    shininess: float
    cavity: float
    double_sided: bool  # drawn without back-face culling (eyes: dark interior; lash cards)
    cutout: bool  # fragments emogenHidden() drops (the cornea of the sclera shell)
    opacity: float  # < 1: alpha-blended, drawn last without depth writes
    fringe_cm: float  # > 0: opacity fades to 0 this far from the fringe root (lash cards)

    @property
    def blended(self) -> bool:
        return self.opacity < 1.0 or self.fringe_cm > 0.0


@dataclass(frozen=True)
class Eye:
    side: int  # 1 left, 2 right
    shell: str  # outer shell with the cornea bulge: gives the eye's centre and axis
    ball: str  # inner ball carrying the iris


@dataclass(frozen=True)
class Look:
    camera: Camera
    background_srgb: tuple[float, float, float]
    size_px: int
    supersample: int  # anti-aliasing: render this many times larger, average down
    footer: str
    parts: tuple[Part, ...]
    eyes: tuple[Eye, ...]
    eye_axis_vertices: int
    fringe_root: str  # region whose nearest vertex measures a fringe vertex's distance
    shader: dict[str, Any]
    framings: dict[str, Camera]
    framing: str  # the framing of ``camera``
    fits: dict[str, tuple[float, float]]  # framing → (fill, top) for cameras fitted to a face
    #: framing → oval mask (centre x, centre y, radius x, radius y) as fractions of the image
    ovals: dict[str, tuple[float, float, float, float]] = field(default_factory=dict)
    #: the wet lower lid margin and the caruncle on the skin (look.json "lid_margin")
    lid_margin: dict[str, float] = field(default_factory=dict)

    @property
    def oval(self) -> tuple[float, float, float, float] | None:
        """The oval mask of the current framing (None: the whole image shows)."""
        return self.ovals.get(self.framing)

    def with_options(
        self,
        *,
        background: tuple[float, float, float] | None = None,
        fov_y_deg: float | None = None,
        camera: Camera | None = None,
        framing: str | None = None,
    ) -> Look:
        """A copy with another background, framing (``face``, ``head``), field of view or camera."""
        if framing is not None and framing not in self.framings:
            raise ConfigError(f"framing must be one of {sorted(self.framings)}; got {framing!r}")
        cam = camera or (self.framings[framing] if framing else self.camera)
        framing = framing or self.framing
        if fov_y_deg is not None:
            if not 1.0 <= fov_y_deg <= 120.0:
                raise ConfigError(f"field of view must be in [1, 120] degrees; got {fov_y_deg}")
            cam = replace(cam, fov_y_deg=float(fov_y_deg))
        return replace(
            self,
            camera=cam,
            framing=framing,
            background_srgb=self.background_srgb if background is None else background,
        )

    def front_irradiance(self) -> float:
        """Linear light reaching a surface that faces the camera (n = +z), green channel, as
        ``emogenLight`` computes it: what the skin generator divides a target colour by."""
        sh = self.shader
        n = np.array([0.0, 0.0, 1.0])
        wrap = float(sh["SKIN_WRAP_RGB"][1])
        total = 0.5 * (np.asarray(sh["GROUND_RGB"]) + np.asarray(sh["SKY_RGB"]))
        for d, rgb in (("KEY_DIR", "KEY_RGB"), ("FILL_DIR", "FILL_RGB")):
            direction = np.asarray(sh[d], dtype=np.float64)
            cos = float(n @ direction / np.linalg.norm(direction))
            total = total + np.asarray(sh[rgb]) * max((cos + wrap) / (1 + wrap), 0.0)
        return float(total[1])

    def glsl_defines(self) -> str:
        """``#define`` lines for ``shade.glsl`` (the viewer's ``glslDefines`` writes the same)."""
        return "".join(f"#define {k} {_glsl_value(v)}\n" for k, v in self.shader.items())


def _glsl_float(x: float) -> str:
    return f"{float(x):.6f}"


def _glsl_value(v: Any) -> str:
    if isinstance(v, list):
        return f"vec{len(v)}({', '.join(_glsl_float(x) for x in v)})"
    return _glsl_float(v)


def _triple(v: Any, what: str) -> tuple[float, float, float]:
    if not isinstance(v, list) or len(v) != 3:
        raise ConfigError(f"look.json: {what} must be 3 numbers; got {v!r}")
    return (float(v[0]), float(v[1]), float(v[2]))


def _oval(mask: Any, name: str) -> tuple[float, float, float, float]:
    cx, cy = mask["centre"]
    rx, ry = mask["radii"]
    values = (float(cx), float(cy), float(rx), float(ry))
    if not all(0 < v <= 1 for v in values):
        raise ConfigError(
            f"look.json: framings.{name}.mask must be fractions in (0, 1]; got {mask}"
        )
    return values


def fitted_look(look: Look, model: FaceModel, appearance: Appearance | None) -> Look:
    """``look`` with its camera fitted to ``model``'s face when its framing fits faces (``face``)
    and the model has landmarks; otherwise ``look`` unchanged."""
    if look.framing not in look.fits or len(model.landmarks) != 68:
        return look
    from emogen.appearance.framing import face_span

    fill, top = look.fits[look.framing]
    hair, chin, depth = face_span(model, appearance or Appearance())
    return replace(look, camera=look.framings[look.framing].fitted(hair, chin, depth, fill, top))


def look_from_dict(d: dict[str, Any]) -> Look:
    """Build a :class:`Look` from parsed ``look.json``, checking the shader's part codes."""
    try:
        framings = {
            name: Camera(
                position=_triple(cam["position_cm"], f"framings.{name}.position_cm"),
                target=_triple(cam["target_cm"], f"framings.{name}.target_cm"),
                up=_triple(cam["up"], f"framings.{name}.up"),
                fov_y_deg=float(cam["fov_y_deg"]),
                near=float(cam["near_cm"]),
                far=float(cam["far_cm"]),
            )
            for name, cam in d["framings"].items()
        }
        if d["framing"] not in framings:
            raise ConfigError(f"look.json: framing {d['framing']!r} is not among the framings")
        camera = framings[d["framing"]]
        fits = {
            name: (float(cam["fill"]), float(cam["top"]))
            for name, cam in d["framings"].items()
            if "fill" in cam
        }
        ovals = {
            name: _oval(cam["mask"], name) for name, cam in d["framings"].items() if "mask" in cam
        }
        parts = tuple(
            Part(
                name=p["name"],
                regions=tuple(p["regions"]),
                albedo_srgb=_triple(p["albedo_srgb"], f"parts.{p['name']}.albedo_srgb"),
                specular=float(p["specular"]),
                shininess=float(p["shininess"]),
                cavity=float(p["cavity"]),
                double_sided=bool(p["double_sided"]),
                cutout=bool(p["cutout"]),
                opacity=float(p["opacity"]),
                fringe_cm=float(p["fringe_cm"]),
            )
            for p in d["parts"]
        )
        eyes = tuple(Eye(int(e["side"]), e["shell"], e["ball"]) for e in d["eyes"])
        look = Look(
            camera=camera,
            background_srgb=_triple(d["background_srgb"], "background_srgb"),
            size_px=int(d["size_px"]),
            supersample=int(d["supersample"]),
            footer=str(d["footer"]),
            parts=parts,
            eyes=eyes,
            eye_axis_vertices=int(d["eye_axis_vertices"]),
            fringe_root=str(d["fringe_root"]),
            shader=dict(d["shader"]),
            framings=framings,
            framing=str(d["framing"]),
            fits=fits,
            ovals=ovals,
            lid_margin={k: float(v) for k, v in d.get("lid_margin", {}).items() if k != "about"},
        )
    except KeyError as exc:
        raise ConfigError(f"look.json lacks {exc}") from None
    names = [p.name for p in parts]
    for key, part in (
        ("PART_SKIN", "skin"),
        ("PART_EYE_SOCKET", "eye_socket"),
        ("PART_SCLERA", "sclera"),
        ("PART_IRIS", "iris"),
    ):
        if part not in names or look.shader.get(key) != names.index(part):
            raise ConfigError(f"look.json: shader.{key} must be the index of part '{part}'")
    return look


@cache
def look_json() -> dict[str, Any]:
    """The packaged ``look.json`` as parsed JSON."""
    text = resources.files("emogen.render").joinpath("look.json").read_text(encoding="utf-8")
    data: dict[str, Any] = json.loads(text)
    return data


def default_look() -> Look:
    return look_from_dict(look_json())


def shade_glsl() -> str:
    """The shared shading functions (``shaders/shade.glsl``)."""
    return (
        resources.files("emogen.render")
        .joinpath("shaders", "shade.glsl")
        .read_text(encoding="utf-8")
    )


def parse_colour(text: str) -> tuple[float, float, float]:
    """``"#808080"``, ``"128,128,128"``, ``"0.5,0.5,0.5"``, ``"white"``/``"black"``/``"grey"`` → sRGB [0, 1]."""
    named = {"white": "#ffffff", "black": "#000000", "grey": "#808080", "gray": "#808080"}
    t = named.get(text.strip().lower(), text.strip())
    try:
        if t.startswith("#") and len(t) == 7:
            return tuple(int(t[i : i + 2], 16) / 255 for i in (1, 3, 5))  # type: ignore[return-value]
        vals = [float(x) for x in t.split(",")]
    except ValueError:
        vals = []
    if len(vals) == 3:
        scale = 255.0 if max(vals) > 1.0 else 1.0
        if all(0 <= v <= scale for v in vals):
            return (vals[0] / scale, vals[1] / scale, vals[2] / scale)
    raise ConfigError(
        f"background must be #rrggbb, R,G,B (0-255 or 0-1) or white/black/grey; got {text!r}"
    )
