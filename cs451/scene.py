"""Scene files: one JSON format for every stage.

A scene names its image, camera, lights, materials and objects. The same
Cornell box can be ray traced (stage 2) and solved by radiosity (stage 4).
Loading validates everything and refuses bad input with the file and the JSON
path of the field (``scenes/box.json: objects[2].radius: must be > 0, got -1``).

Field defaults follow OpenGL 1.x where OpenGL has one (GL 2.1 spec, table 6.11
and Mesa's light.c), so the stage-1 sphere reproduces the fixed-function pipeline.
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from . import schema
from .errors import InputError, KitError
from .schema import Context, Tagged, Vec3, field

BUNDLED_DIR = Path(__file__).parent / "scenes"


@dataclass(frozen=True)
class Image:
    width: int = field("Image width in pixels.", 500, schema.positive)
    height: int = field("Image height in pixels.", 500, schema.positive)
    background: Vec3 = field("Linear RGB colour where nothing is drawn.", (0.0, 0.0, 0.0), schema.non_negative)
    exposure: float = field("Linear colours are multiplied by this before encoding.", 1.0, schema.positive)
    srgb: bool = field("Encode with the sRGB curve when writing 8-bit images (false: write linear values, as OpenGL 1.x did).", False)

    def validate(self, ctx: Context) -> None:
        from .limits import check_image_size
        problem = check_image_size(self.width, self.height, "the image")
        if problem:
            raise ctx.child("width").error(problem)


#: the narrowest field of view (and 180° less it, the widest), in degrees
MIN_FOVY = 0.01
#: the largest far/near ratio: a 24-bit depth buffer loses all precision past about 10⁶
MAX_DEPTH_RATIO = 1e6


@dataclass(frozen=True)
class Camera:
    eye: Vec3 = field("Eye position (gluLookAt's eye).")
    center: Vec3 = field("Point looked at (gluLookAt's center).")
    up: Vec3 = field("Up direction (gluLookAt's up); must not be parallel to the view direction.", (0.0, 1.0, 0.0), schema.nonzero_vector)
    fovy: float = field("Vertical field of view in degrees (gluPerspective's fovy).", 30.0)
    near: float = field("Near clipping distance (> 0).", 0.1, schema.positive)
    far: float = field("Far clipping distance (> near).", 1000.0, schema.positive)

    def validate(self, ctx: Context) -> None:
        if not MIN_FOVY <= self.fovy <= 180 - MIN_FOVY:
            raise ctx.child("fovy").error(f"must lie between {MIN_FOVY} and {180 - MIN_FOVY} degrees (the projection's "
                                          f"scale is cot(fovy/2)), got {self.fovy}")
        if self.far <= self.near:
            raise ctx.child("far").error(f"must be greater than near ({self.near}), got {self.far}")
        if self.far / self.near > MAX_DEPTH_RATIO:
            raise ctx.child("far").error(f"must be at most {MAX_DEPTH_RATIO:g} × near (a depth buffer cannot tell "
                                         f"depths apart beyond that), got far/near = {self.far / self.near:.3g}")
        view = [c - e for c, e in zip(self.center, self.eye)]
        if max(abs(c) for c in view) <= max(schema.MIN_LENGTH, 1e-12 * max(map(abs, (*self.eye, *self.center)))):
            raise ctx.child("center").error(f"must differ from eye {list(self.eye)} (the view direction is center - "
                                            f"eye), got {list(self.center)}")
        cross = (view[1] * self.up[2] - view[2] * self.up[1],
                 view[2] * self.up[0] - view[0] * self.up[2],
                 view[0] * self.up[1] - view[1] * self.up[0])
        if max(abs(c) for c in cross) <= 1e-12 * max(abs(v) for v in view) * max(abs(u) for u in self.up):
            raise ctx.child("up").error("must not be parallel to the view direction (center - eye)")


class Light(Tagged, family=True):
    """A light source; the ``type`` key picks the kind."""


@Light.register("point")
@dataclass(frozen=True)
class PointLight(Light):
    position: Vec3 = field("Position of the light.")
    space: Literal["world", "eye"] = field(
        "Coordinates of `position`: 'world', or 'eye' for a light fixed to the camera "
        "(OpenGL's glLightfv under an identity modelview).", "world")
    ambient: Vec3 = field("Ambient colour (GL_AMBIENT).", (0.0, 0.0, 0.0), schema.non_negative)
    diffuse: Vec3 = field("Diffuse colour (GL_DIFFUSE; the default is GL_LIGHT0's, for every light); also the intensity for ray tracing.", (1.0, 1.0, 1.0), schema.non_negative)
    specular: Vec3 = field("Specular colour (GL_SPECULAR).", (1.0, 1.0, 1.0), schema.non_negative)
    attenuation: Vec3 = field("Constant, linear and quadratic attenuation factors.", (1.0, 0.0, 0.0), schema.non_negative)

    def validate(self, ctx: Context) -> None:
        if not any(self.attenuation):
            raise ctx.child("attenuation").error("must not all be zero (the light would be infinitely bright)")


@Light.register("directional")
@dataclass(frozen=True)
class DirectionalLight(Light):
    direction: Vec3 = field("Direction the light travels (towards the scene).", check=schema.nonzero_vector)
    space: Literal["world", "eye"] = field("Coordinates of `direction`.", "world")
    ambient: Vec3 = field("Ambient colour.", (0.0, 0.0, 0.0), schema.non_negative)
    diffuse: Vec3 = field("Diffuse colour.", (1.0, 1.0, 1.0), schema.non_negative)
    specular: Vec3 = field("Specular colour.", (1.0, 1.0, 1.0), schema.non_negative)


#: the most shadow rays per area light and shading point: a 64 × 64 grid. Each is a light sample that every
#: shading point visits, so 10⁶ of them turn a second's render into days
MAX_LIGHT_SAMPLES = 4096
LIGHT_SAMPLES_WHY = "a 64 × 64 grid; every shading point casts one shadow ray to each"


@Light.register("area")
@dataclass(frozen=True)
class AreaLight(Light):
    corner: Vec3 = field("One corner of the rectangular light.")
    edge_u: Vec3 = field("First edge vector from the corner.", check=schema.nonzero_vector)
    edge_v: Vec3 = field("Second edge vector from the corner; the light emits on the side of edge_u × edge_v.", check=schema.nonzero_vector)
    radiance: Vec3 = field("Emitted radiance (linear RGB).", check=schema.non_negative)
    samples: int = field("Shadow rays per shading point (ray tracing).", 16,
                         schema.between(1, MAX_LIGHT_SAMPLES, LIGHT_SAMPLES_WHY))

    def validate(self, ctx: Context) -> None:
        u, v = self.edge_u, self.edge_v
        scale = max(abs(c) for c in u) * max(abs(c) for c in v)
        cross = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
        if max(abs(c) for c in cross) <= 1e-9 * scale:
            raise ctx.child("edge_v").error(f"is parallel to edge_u {list(u)}: the light would have no area, got "
                                            f"{list(v)}")


@dataclass(frozen=True)
class Material:
    ambient: Vec3 = field("Ambient reflectance (GL_AMBIENT).", (0.2, 0.2, 0.2), schema.non_negative)
    diffuse: Vec3 = field("Diffuse reflectance (GL_DIFFUSE); the albedo for radiosity.", (0.8, 0.8, 0.8), schema.unit_interval)
    specular: Vec3 = field("Specular reflectance (GL_SPECULAR); for stage 4, k_s of the highlight's normalised Phong lobe.",
                           (0.0, 0.0, 0.0), schema.non_negative)
    shininess: float = field("Phong exponent (GL_SHININESS, 0..128 in OpenGL); for stage 4, the lobe's n (0: no highlight).",
                             0.0, schema.non_negative)
    emission: Vec3 = field("Emitted colour (GL_EMISSION); the emitted radiosity for stage 4.", (0.0, 0.0, 0.0), schema.non_negative)
    reflectance: Vec3 = field("Mirror reflectance for ray tracing.", (0.0, 0.0, 0.0), schema.unit_interval)
    transmittance: Vec3 = field("Transmittance for ray tracing.", (0.0, 0.0, 0.0), schema.unit_interval)
    ior: float = field("Index of refraction of the inside.", 1.0, schema.positive)
    fresnel: bool = field("Weight reflection and transmission by Fresnel's equations.", False)


class Object(Tagged, family=True):
    """A geometric object; the ``type`` key picks the kind."""


@Object.register("sphere")
@dataclass(frozen=True)
class Sphere(Object):
    radius: float = field("Radius.", check=schema.positive)
    center: Vec3 = field("Centre.", (0.0, 0.0, 0.0))
    material: str = field("Name of a material in `materials`.", "default")
    slices: int = field("Tessellation around the z axis, for rasterising (glutSolidSphere's slices).", 32, schema.at_least(3))
    stacks: int = field("Tessellation along the z axis, for rasterising (glutSolidSphere's stacks).", 32, schema.at_least(2))


@Object.register("plane")
@dataclass(frozen=True)
class Plane(Object):
    point: Vec3 = field("A point on the plane.")
    normal: Vec3 = field("Normal of the plane.", check=schema.nonzero_vector)
    material: str = field("Name of a material in `materials`.", "default")
    checker: float = field("Size of a checkerboard's squares (0: plain).", 0.0, schema.non_negative)
    checker_material: str = field("Material of the odd squares of the checkerboard.", "default")


#: the most corners of one polygon: past a few thousand a shape is a mesh (an OBJ file), and a polygon's corners
#: are each checked in Python as the scene loads
MAX_POLYGON_VERTICES = 10_000

#: how far a polygon's corner may lie off its plane, as a fraction of its size (the Cornell box's
#: measured walls are off by up to 0.14%)
NON_PLANAR = 0.01


@Object.register("polygon")
@dataclass(frozen=True)
class Polygon(Object):
    vertices: list[Vec3] = field("Corners of a planar convex polygon, counter-clockwise seen from the front "
                                 f"(3 to {MAX_POLYGON_VERTICES:,}).", check=schema.max_items(MAX_POLYGON_VERTICES,
                                 "a larger shape is a mesh: an OBJ file"))
    material: str = field("Name of a material in `materials`.", "default")

    def validate(self, ctx: Context) -> None:
        import numpy as np  # local: keeps scene loading cheap for tools that never validate polygons
        v = np.asarray(self.vertices, dtype=float)
        if len(v) < 3:
            raise ctx.child("vertices").error(f"needs at least 3 vertices, got {len(v)}")
        repeated = np.flatnonzero((v == np.roll(v, -1, axis=0)).all(axis=1))
        if len(repeated):
            k = int(repeated[0])
            raise ctx.child("vertices").child((k + 1) % len(v)).error(
                f"repeats the corner before it, {list(self.vertices[k])} (a degenerate edge: drop one)")
        n = np.cross(v, np.roll(v, -1, axis=0)).sum(axis=0)   # Newell's normal: robust for any planar polygon
        scale = max(float(np.ptp(v, axis=0).max()), 1e-300)
        if np.linalg.norm(n) <= 1e-12 * scale * scale:
            raise ctx.child("vertices").error("degenerate polygon (zero area: repeated or collinear vertices)")
        n = n / np.linalg.norm(n)
        off = np.abs((v - v.mean(axis=0)) @ n)   # distances from the mean plane
        if off.max() > NON_PLANAR * scale:
            k = int(off.argmax())
            raise ctx.child("vertices").child(k).error(
                f"the polygon is not planar: this corner is {off[k]:.4g} off its plane, {off[k] / scale:.1%} of the "
                f"polygon's size (at most {NON_PLANAR:.0%}; split it into triangles)")
        edges = np.roll(v, -1, axis=0) - v
        turns = np.cross(edges, np.roll(edges, -1, axis=0)) @ n   # each corner's turn, against the normal
        reflex = np.flatnonzero(turns < -1e-9 * scale * scale)
        if len(reflex):   # a fan from the first corner would cover ground outside the polygon, or twice
            k = (int(reflex[0]) + 1) % len(v)
            raise ctx.child("vertices").child(k).error(
                f"the polygon is not convex: it turns the wrong way at this corner, {list(self.vertices[k])} "
                f"(split it into convex polygons or triangles)")


@Object.register("mesh")
@dataclass(frozen=True)
class Mesh(Object):
    file: str = field("OBJ file, relative to the scene file.")
    material: str = field("Name of a material in `materials`.", "default")
    scale: float = field("Uniform scale applied to the mesh.", 1.0, schema.positive)
    translate: Vec3 = field("Translation applied after scaling.", (0.0, 0.0, 0.0))


class Transform(Tagged, family=True):
    """One call of OpenGL 1.x's modelview matrix (glTranslate, glRotate, glScale); the ``type`` key picks it."""


@Transform.register("translate")
@dataclass(frozen=True)
class Translate(Transform):
    offset: Vec3 = field("glTranslate(x, y, z): the offset.")

    @property
    def call(self) -> tuple:
        return ("translate", *map(float, self.offset))


@Transform.register("rotate")
@dataclass(frozen=True)
class Rotate(Transform):
    angle: float = field("glRotate's angle in degrees, counter-clockwise looking from the axis' tip to the origin.")
    axis: Vec3 = field("glRotate's axis (any length; OpenGL normalises it).", check=schema.nonzero_vector)

    @property
    def call(self) -> tuple:
        return ("rotate", float(self.angle), *map(float, self.axis))


def _nonzero_factors(v: Any) -> str | None:
    return "no factor may be 0 (the normals could not be transformed)" if any(c == 0 for c in v) else None


@Transform.register("scale")
@dataclass(frozen=True)
class Scale(Transform):
    factors: Vec3 = field("glScale(x, y, z): the factors along each axis (none 0).", check=_nonzero_factors)

    @property
    def call(self) -> tuple:
        return ("scale", *map(float, self.factors))


#: OpenGL guarantees a modelview stack of at least 32 matrices (GL_MAX_MODELVIEW_STACK_DEPTH): the view, then
#: one push per group
MAX_GROUP_DEPTH = 31


@Object.register("group")
@dataclass(frozen=True)
class Group(Object):
    """Objects placed together: the transforms apply to every child, as calls between glPushMatrix and glPopMatrix."""
    objects: list[Object] = field("The objects of the group (spheres, or groups again).")
    transform: list[Transform] = field(
        "Calls in the order a program makes them (translate, rotate, scale); the last is the first applied to the "
        "objects.", [])


def walk_objects(objects: list, ctx: Context | None = None, depth: int = 0):
    """Every object that is not a group, in drawing order, with its JSON context (``objects[2].objects[0]``)."""
    ctx = ctx or Context("")
    for k, obj in enumerate(objects):
        sub = ctx.child("objects").child(k)
        if isinstance(obj, Group):
            if depth >= MAX_GROUP_DEPTH:
                raise sub.error(f"groups nest at most {MAX_GROUP_DEPTH} deep (OpenGL's modelview stack holds 32 "
                                f"matrices)")
            yield from walk_objects(obj.objects, sub, depth + 1)
        else:
            yield obj, sub


@dataclass(frozen=True)
class Scene:
    camera: Camera = field("The viewpoint.")
    name: str = field("Short name.", "")
    description: str = field("One line about the scene.", "")
    image: Image = field("Output image settings.", Image())
    ambient: Vec3 = field("Global ambient light (GL_LIGHT_MODEL_AMBIENT).", (0.2, 0.2, 0.2), schema.non_negative)
    lights: list[Light] = field("Light sources.", [])
    materials: dict[str, Material] = field("Materials by name; 'default' exists unless redefined.", {})
    objects: list[Object] = field("Geometry.", [])
    options: dict[str, dict[str, Any]] = field("Per-stage options, e.g. {\"sphere\": {\"shading\": \"phong\"}}; each stage validates its own.", {})
    source: str = field("Where the scene was loaded from (set by the loader).", "")

    def validate(self, ctx: Context) -> None:
        known = set(self.materials) | {"default"}
        for obj, where in walk_objects(self.objects, ctx):
            for key in ("material", "checker_material"):
                name = getattr(obj, key, None)
                if name is not None and name not in known:
                    raise where.child(key).error(f"unknown material {name!r} (defined: {', '.join(sorted(known))})")

    def material(self, name: str) -> Material:
        return self.materials.get(name, Material())

    @property
    def label(self) -> str:
        """What messages call the scene: a bundled scene by its name, another by its file, else its name."""
        if self.source and Path(self.source).parent == BUNDLED_DIR:
            return f"{Path(self.source).stem} (bundled scene)"
        return self.source or self.name or "<scene>"


def bundled_scenes() -> list[str]:
    """Names of the scenes shipped with the kit."""
    return sorted(p.stem for p in BUNDLED_DIR.glob("*.json"))


def resolve_scene_path(name_or_path: str | Path) -> Path:
    """A bundled scene name (``sphere``) or a path to a JSON file.

    A bundled name wins over a folder of the same name (a student's repository holds a
    package folder named after its stage, ``whitted/``, beside the bundled scene ``whitted``).
    Anything that is not a regular file is named as what it is, never opened: a FIFO would block the read and
    ``/dev/zero`` would fill memory.
    """
    p = Path(name_or_path)
    bundled = BUNDLED_DIR / f"{name_or_path}.json"
    if "/" not in str(name_or_path) and p.suffix != ".json" and not p.is_file() and bundled.exists():
        return bundled
    kind = file_kind(p)
    if kind == "file":
        return p
    if kind == "missing" and p.suffix != ".json" and "/" not in str(name_or_path):
        raise KitError(f"unknown scene {str(name_or_path)!r}: not a file, and not a bundled scene"
                       f"{schema.suggestion(name_or_path, bundled_scenes())} (bundled: {', '.join(bundled_scenes())})")
    if kind == "missing":
        raise KitError(f"{p}: scene file not found")
    raise KitError(f"{p}: {kind}, not a scene file (a scene is a JSON file; bundled scenes: "
                   f"{', '.join(bundled_scenes())})")


def file_kind(path: Path) -> str:
    """What ``path`` is, for messages: "file", "missing", or what else it is ("a folder", "a named pipe
    (FIFO)", "a character device (/dev/zero)"), found without opening it."""
    import stat
    try:
        mode = path.stat().st_mode     # follows a link: a link to /dev/zero is a device
    except FileNotFoundError:
        return "a broken symbolic link" if path.is_symlink() else "missing"
    except OSError as err:
        return f"unreadable ({err.strerror})"
    if stat.S_ISREG(mode):
        return "file"
    target = f" ({path.resolve()})" if path.is_symlink() else ""
    kinds = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a named pipe (FIFO)"), (stat.S_ISCHR, "a character device"),
             (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))
    return next((f"{what}{target}" for test, what in kinds if test(mode)), f"not a regular file{target}")


#: the largest scene file: the bundled ones are a few kilobytes, and a JSON file of this size already takes a
#: few hundred megabytes as Python objects; big geometry belongs in an OBJ mesh
MAX_SCENE_BYTES = 16 * 2**20
#: the most objects in a scene, counted before any is parsed (groups' children included)
MAX_OBJECTS = 100_000

TOO_DEEP = f"nested too deeply (groups nest at most {MAX_GROUP_DEPTH} deep)"


def load_scene(name_or_path: str | Path) -> Scene:
    """Load and validate a scene; raises InputError naming the file and field on bad input."""
    path = resolve_scene_path(name_or_path)
    label = str(path) if path.parent != BUNDLED_DIR else f"{path.stem} (bundled scene {path.name})"
    size = path.stat().st_size
    if size > MAX_SCENE_BYTES:
        raise InputError(label, "", f"{size / 2**20:.1f} MB, over the {MAX_SCENE_BYTES // 2**20} MB a scene file may "
                                    f"be (put large geometry in an OBJ file and name it in a mesh object)")
    try:
        text = path.read_bytes().decode("utf-8")
        data = json.loads(text, parse_constant=_refuse_constant, object_pairs_hook=schema.json_object)
    except UnicodeDecodeError as err:
        raise InputError(label, f"byte {err.start}", "not UTF-8 text (a scene file is JSON)") from None
    except json.JSONDecodeError as err:
        raise InputError(label, f"line {err.lineno} column {err.colno}", f"invalid JSON: {err.msg}") from None
    except ValueError as err:
        raise InputError(label, "", str(err)) from None
    except RecursionError:
        raise InputError(label, "", TOO_DEEP) from None
    except OSError as err:
        raise InputError(label, "", f"cannot be read ({err.strerror})") from None
    return parse_scene(data, label, source=str(path))


def _count_objects(objects: Any, depth: int = 0) -> int:
    if not isinstance(objects, list) or depth > MAX_GROUP_DEPTH:
        return 0
    return len(objects) + sum(_count_objects(o.get("objects"), depth + 1) for o in objects if isinstance(o, dict))


def parse_scene(data: Any, label: str = "<scene>", source: str = "") -> Scene:
    """Validate a scene given as a JSON-like dict (Mitsuba-style: scenes are plain dicts too)."""
    if isinstance(data, dict):
        if "source" in data:
            raise InputError(label, "source", "unknown field (set by the loader, not by the file)")
        count = _count_objects(data.get("objects"))
        if count > MAX_OBJECTS:
            raise InputError(label, "objects", f"{count:,} objects, over the {MAX_OBJECTS:,} a scene may hold (a "
                                               f"large shape belongs in an OBJ file, named by one mesh object)")
        if isinstance(data.get("$schema"), str):   # an editor's pointer to docs/scene.schema.json
            data = {k: v for k, v in data.items() if k != "$schema"}
    try:
        scene = schema.parse_record(Scene, data, Context(label))
    except RecursionError:
        raise InputError(label, "objects", TOO_DEEP) from None
    object.__setattr__(scene, "source", source)
    return scene


def _refuse_constant(name: str) -> Any:
    # json accepts NaN and Infinity by default; a scene must never carry them
    raise ValueError(f"{name} is not allowed in a scene file (use finite numbers)")
