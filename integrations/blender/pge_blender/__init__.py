"""PGE for Blender: grow a PGE script's model into the scene, and again on every change.

The "PGE" tab of the 3D view's sidebar picks a script (a file, or one of the library's), shows
the parameters it declares (`pge.params`) as properties with the script's bounds and docs,
the seed and the steps. "Generate" runs the script and imports its glb into the "PGE"
collection under an empty named after the script: generating again replaces what is under
that empty and keeps the empty's transform. A forest's trees arrive as linked duplicates
(objects sharing one mesh per variant), never as copies of the mesh. "Live" regenerates when
the script or a file it read is saved, and shortly after a property changes. A failing
script shows `FILE:LINE: message` in the panel and the operator's report; the scene keeps
the previous result.

It generates with the `pge` Python module when Blender's Python has it
(`pip install ./integrations/python` into it), otherwise with the `pge` program (the
add-on's preferences, or the PATH); the parameters are listed only with the module.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any, Optional

import bpy
from bpy.props import (
    BoolProperty,
    EnumProperty,
    FloatProperty,
    IntProperty,
    PointerProperty,
    StringProperty,
)

try:
    import pge as pge_module
except ImportError:
    pge_module = None

#: The collection every result goes to.
COLLECTION = "PGE"
#: Seconds between two looks at the watched files, with Live on.
WATCH_INTERVAL = 0.5
#: Seconds after the last property change before Live regenerates.
DEBOUNCE = 0.4


class GenerateError(Exception):
    """A generation that failed: the text is `FILE:LINE: message` for a script's error."""


# --- generating: the module, or the pge program ----------------------------------------


def _preferences() -> Optional[Any]:
    addon = bpy.context.preferences.addons.get(__package__)
    return addon.preferences if addon else None


def library_folder() -> Optional[str]:
    """The script library: the preferences' folder, `$PGE_LIBRARY`, or the module's."""
    prefs = _preferences()
    if prefs and prefs.library:
        return bpy.path.abspath(prefs.library)
    if os.environ.get("PGE_LIBRARY"):
        return os.environ["PGE_LIBRARY"]
    if pge_module is not None:
        return pge_module.library()
    return None


def _pge_program() -> Optional[str]:
    prefs = _preferences()
    if prefs and prefs.program:
        return bpy.path.abspath(prefs.program)
    return shutil.which("pge")


def backend() -> str:
    """What generates: "module", "program" or "" (nothing found)."""
    if pge_module is not None:
        return "module"
    return "program" if _pge_program() else ""


def _environment() -> dict[str, str]:
    env = dict(os.environ)
    library = library_folder()
    if library:
        env["PGE_LIBRARY"] = library
    return env


def run_script(
    script: str, params: dict[str, Any], seed: int, steps: Optional[int]
) -> tuple[bytes, list[str]]:
    """The glb of `script` and the files the run read (to watch)."""
    if pge_module is not None:
        library = library_folder()
        saved = os.environ.get("PGE_LIBRARY")
        if library:
            os.environ["PGE_LIBRARY"] = library
        try:
            result = pge_module.generate(script, params=params, seed=seed, steps=steps)
        except pge_module.ScriptError as e:
            raise GenerateError(str(e)) from e
        except (TypeError, ValueError) as e:
            raise GenerateError(f"{script}: {e}") from e
        finally:
            if library:
                if saved is None:
                    os.environ.pop("PGE_LIBRARY", None)
                else:
                    os.environ["PGE_LIBRARY"] = saved
        for warning in result.warnings:
            print(warning)
        return result.glb, list(result.files)
    program = _pge_program()
    if not program:
        raise GenerateError(
            "PGE: neither the pge Python module nor the pge program was found "
            "(pip install ./integrations/python, or set the program in the preferences)"
        )
    with tempfile.TemporaryDirectory(prefix="pge-") as tmp:
        out = os.path.join(tmp, "model.glb")
        args = [program, "run", script, "-o", out, "-q", "--seed", str(seed)]
        if steps is not None:
            args += ["--steps", str(steps)]
        for name, value in params.items():
            text = str(value).lower() if isinstance(value, bool) else repr(value)
            if isinstance(value, str):
                text = value
            args += ["--set", f"{name}={text}"]
        done = subprocess.run(args, capture_output=True, text=True, env=_environment())
        if done.returncode != 0:
            lines = done.stderr.strip().splitlines()
            raise GenerateError(lines[-1] if lines else f"pge exited with {done.returncode}")
        with open(out, "rb") as f:
            glb = f.read()
    return glb, [script]


def declared_params(script: str) -> dict[str, dict[str, Any]]:
    """The parameters `script` declares (empty without the module)."""
    if pge_module is None:
        return {}
    try:
        return pge_module.params(script)
    except pge_module.ScriptError as e:
        raise GenerateError(str(e)) from e


# --- the script's parameters as properties ----------------------------------------------

_params_class: Optional[type] = None


def _param_property(name: str, spec: dict[str, Any]) -> Any:
    default = spec["default"]
    common = {"name": name, "description": spec.get("doc") or "", "update": _on_change}
    lo, hi = spec.get("min"), spec.get("max")
    if isinstance(default, bool):
        return BoolProperty(default=default, **common)
    if isinstance(default, int):
        bounds = {}
        if lo is not None:
            bounds["min"] = int(-(-lo // 1))
        if hi is not None:
            bounds["max"] = int(hi // 1)
        return IntProperty(default=default, **bounds, **common)
    if isinstance(default, float):
        bounds = {}
        if lo is not None:
            bounds["min"] = float(lo)
        if hi is not None:
            bounds["max"] = float(hi)
        return FloatProperty(default=default, **bounds, **common)
    return StringProperty(default=str(default), **common)


def _drop_params() -> None:
    global _params_class
    if _params_class is not None:
        del bpy.types.Scene.pge_params
        bpy.utils.unregister_class(_params_class)
        _params_class = None


def set_params(declared: dict[str, dict[str, Any]]) -> None:
    """Makes `scene.pge_params` hold `declared`, each at its default."""
    global _params_class
    _drop_params()
    annotations = {name: _param_property(name, spec) for name, spec in declared.items()}
    _params_class = type(
        "PGE_PG_params", (bpy.types.PropertyGroup,), {"__annotations__": annotations}
    )
    bpy.utils.register_class(_params_class)
    bpy.types.Scene.pge_params = PointerProperty(type=_params_class)


def param_values(scene: bpy.types.Scene) -> dict[str, Any]:
    """The parameters the user changed (the others keep the script's exact defaults)."""
    if _params_class is None:
        return {}
    group = scene.pge_params
    return {
        name: getattr(group, name)
        for name in _params_class.__annotations__
        if group.is_property_set(name)
    }


# --- importing ---------------------------------------------------------------------------


def _collection(scene: bpy.types.Scene) -> bpy.types.Collection:
    coll = bpy.data.collections.get(COLLECTION)
    if coll is None:
        coll = bpy.data.collections.new(COLLECTION)
    if coll.name not in scene.collection.children:
        scene.collection.children.link(coll)
    return coll


def _layer_collection(layer: Any, coll: bpy.types.Collection) -> Any:
    if layer.collection == coll:
        return layer
    for child in layer.children:
        found = _layer_collection(child, coll)
        if found:
            return found
    return None


def _import_glb(context: Any, glb: bytes, into: bpy.types.Collection) -> list[Any]:
    """Imports `glb` into a new collection inside `into`; returns it and its objects."""
    staging = bpy.data.collections.new("PGE import")
    into.children.link(staging)
    view_layer = context.view_layer
    active = view_layer.active_layer_collection
    view_layer.active_layer_collection = _layer_collection(
        view_layer.layer_collection, staging
    )
    fd, path = tempfile.mkstemp(prefix="pge-", suffix=".glb")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(glb)
        result = bpy.ops.import_scene.gltf(filepath=path)
    finally:
        os.unlink(path)
        view_layer.active_layer_collection = active
    objects = list(staging.objects)
    for obj in objects:
        into.objects.link(obj)
        staging.objects.unlink(obj)
    bpy.data.collections.remove(staging)
    if result != {"FINISHED"}:
        for obj in objects:
            bpy.data.objects.remove(obj)
        raise GenerateError(f"Blender's glTF importer returned {result}")
    return objects


def _remove(objects: list[Any]) -> None:
    """Removes `objects` and the meshes, materials and images only they used."""
    meshes = {o.data for o in objects if o.type == "MESH" and o.data}
    materials = {m for mesh in meshes for m in mesh.materials if m}
    for obj in objects:
        bpy.data.objects.remove(obj)
    for mesh in meshes:
        if mesh.users == 0:
            bpy.data.meshes.remove(mesh)
    images = set()
    for mat in materials:
        if mat.users == 0:
            if mat.node_tree:
                images |= {n.image for n in mat.node_tree.nodes if getattr(n, "image", None)}
            bpy.data.materials.remove(mat)
    for image in images:
        if image.users == 0:
            bpy.data.images.remove(image)


def generate(context: Any) -> Any:
    """Generates the scene's script into the PGE collection; returns the result's empty.

    Raises GenerateError (the scene as it was) when the script fails.
    """
    scene = context.scene
    settings = scene.pge
    if not settings.script:
        raise GenerateError("PGE: no script chosen")
    script = bpy.path.abspath(settings.script)
    steps = settings.steps if settings.steps > 0 else None
    glb, files = run_script(script, param_values(scene), settings.seed, steps)
    coll = _collection(scene)
    objects = _import_glb(context, glb, coll)
    root = settings.target
    if root is None or root.name not in bpy.data.objects:
        root = bpy.data.objects.new(Path(script).stem, None)
        root.empty_display_type = "PLAIN_AXES"
        coll.objects.link(root)
    old = list(root.children_recursive)
    for obj in objects:
        if obj.parent is None:
            obj.parent = root
    _remove(old)
    root["pge_script"] = script
    settings.target = root
    settings.error = ""
    _watch["mtimes"] = {f: _mtime(f) for f in files}
    return root


# --- Live --------------------------------------------------------------------------------

_watch: dict[str, Any] = {"mtimes": {}, "due": None}


def _mtime(path: str) -> float:
    try:
        return os.stat(path).st_mtime
    except OSError:
        return -1.0


def _regenerate(context: Any) -> None:
    try:
        generate(context)
    except GenerateError as e:
        context.scene.pge.error = str(e)
        print(f"PGE: {e}")


def watch() -> Optional[float]:
    """The Live timer: regenerates when a watched file changed or a change is due."""
    scene = bpy.context.scene
    if scene is None or not scene.pge.live:
        return None
    now = time.monotonic()
    changed = any(_mtime(f) != m for f, m in _watch["mtimes"].items())
    due = _watch["due"] is not None and now >= _watch["due"]
    if changed or due:
        _watch["due"] = None
        _regenerate(bpy.context)
    return WATCH_INTERVAL


def _on_change(self: Any, context: Any) -> None:
    if context.scene.pge.live:
        _watch["due"] = time.monotonic() + DEBOUNCE


def _on_live(self: Any, context: Any) -> None:
    if self.live:
        _watch["due"] = time.monotonic()
        if not bpy.app.timers.is_registered(watch):
            bpy.app.timers.register(watch, first_interval=WATCH_INTERVAL)
    elif bpy.app.timers.is_registered(watch):
        bpy.app.timers.unregister(watch)


def _on_script(self: Any, context: Any) -> None:
    script = bpy.path.abspath(self.script) if self.script else ""
    try:
        set_params(declared_params(script) if script else {})
        self.error = ""
    except GenerateError as e:
        set_params({})
        self.error = str(e)
    _on_change(self, context)


_library_items: list[tuple[str, str, str]] = []


def _library_scripts(self: Any, context: Any) -> list[tuple[str, str, str]]:
    folder = library_folder()
    items = [("", "(choose)", "Pick one of the library's scripts")]
    if folder and os.path.isdir(folder):
        for path in sorted(Path(folder).glob("*/*.lua")):
            rel = path.relative_to(folder).as_posix()
            items.append((str(path), rel, f"The library's {rel}"))
    # Blender keeps only pointers to the strings: they must outlive the call.
    _library_items[:] = items
    return _library_items


def _on_library_script(self: Any, context: Any) -> None:
    if self.library_script:
        self.script = self.library_script


# --- the UI ------------------------------------------------------------------------------


class PGE_Preferences(bpy.types.AddonPreferences):
    """Where the script library and the pge program are."""

    bl_idname = __package__

    library: StringProperty(
        name="Script library",
        subtype="DIR_PATH",
        description="The scripts/ folder of PGE (default: $PGE_LIBRARY or the module's)",
    )
    program: StringProperty(
        name="pge program",
        subtype="FILE_PATH",
        description="The pge program, used without the Python module (default: the PATH's)",
    )

    def draw(self, context: Any) -> None:
        self.layout.prop(self, "library")
        self.layout.prop(self, "program")


class PGE_PG_settings(bpy.types.PropertyGroup):
    """The scene's PGE settings."""

    script: StringProperty(
        name="Script", subtype="FILE_PATH", description="The Lua script", update=_on_script
    )
    library_script: EnumProperty(
        name="Library", description="One of the library's scripts", items=_library_scripts,
        update=_on_library_script,
    )
    seed: IntProperty(
        name="Seed", default=1, min=0, description="Seed of every random draw",
        update=_on_change,
    )
    steps: IntProperty(
        name="Steps", default=0, min=0,
        description="Steps to run instead of the algorithm's own count (0: its own)",
        update=_on_change,
    )
    live: BoolProperty(
        name="Live", description="Regenerate when the script or a file it reads is saved, "
        "and when a property changes", update=_on_live,
    )
    error: StringProperty(name="Error")
    target: PointerProperty(type=bpy.types.Object, name="Result")


class PGE_OT_generate(bpy.types.Operator):
    """Run the script and import its model into the PGE collection"""

    bl_idname = "pge.generate"
    bl_label = "Generate"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context: Any) -> set[str]:
        try:
            root = generate(context)
        except GenerateError as e:
            context.scene.pge.error = str(e)
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.report({"INFO"}, f"PGE: {root.name} generated")
        return {"FINISHED"}


class PGE_PT_panel(bpy.types.Panel):
    """The PGE tab of the 3D view's sidebar."""

    bl_label = "PGE"
    bl_idname = "PGE_PT_panel"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "PGE"

    def draw(self, context: Any) -> None:
        layout = self.layout
        settings = context.scene.pge
        layout.prop(settings, "library_script")
        layout.prop(settings, "script")
        if _params_class is not None and _params_class.__annotations__:
            box = layout.box()
            for name in _params_class.__annotations__:
                box.prop(context.scene.pge_params, name)
        elif settings.script and pge_module is None:
            layout.label(text="Parameters need the pge Python module")
        layout.prop(settings, "seed")
        layout.prop(settings, "steps")
        row = layout.row()
        row.operator(PGE_OT_generate.bl_idname)
        row.prop(settings, "live", toggle=True)
        if settings.error:
            box = layout.box()
            box.alert = True
            for i, line in enumerate(_wrap(settings.error, 60)):
                box.label(text=line, icon="ERROR" if i == 0 else "NONE")
        if not backend():
            layout.label(text="No pge module or program found", icon="ERROR")


def _wrap(text: str, width: int) -> list[str]:
    words, lines, line = text.split(), [], ""
    for word in words:
        if line and len(line) + 1 + len(word) > width:
            lines.append(line)
            line = word
        else:
            line = f"{line} {word}" if line else word
    if line:
        lines.append(line)
    return lines


CLASSES = (PGE_Preferences, PGE_PG_settings, PGE_OT_generate, PGE_PT_panel)


def register() -> None:
    """Registers the add-on's classes and the scene's settings."""
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.pge = PointerProperty(type=PGE_PG_settings)


def unregister() -> None:
    """Removes what register added, and stops Live."""
    if bpy.app.timers.is_registered(watch):
        bpy.app.timers.unregister(watch)
    _drop_params()
    del bpy.types.Scene.pge
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
