"""The render settings as the Blender add-on stores them, derived from the core's settings table
(``photonsplat.SETTINGS``: name, type, default, range, choices, unit, description, deprecated aliases per setting).

No bpy here: ``properties.py`` turns ``property_specs()`` into Blender properties, and the exporter turns
``scene.photonsplat`` back into ``RenderSettings`` keyword arguments with ``render_settings_kwargs(props)``. A
setting added to the core's table appears in both without a change here; this module only adds how Blender
shows it (labels, slider ranges), which has fallbacks.
"""

try:
    from ._core import SETTINGS
except ImportError:  # pragma: no cover - a broken build: the add-on registers and its panel says why
    SETTINGS = ()

# Settings Blender takes from its own controls rather than from scene.photonsplat: the view layer's passes
# (outputs, and the Caustics pass) and the film's Transparent toggle.
FROM_BLENDER = frozenset({"outputs", "caustics_pass", "transparent"})

# Blender stores memory in GiB (a float), the core in bytes.
GIB = 2**30

# Blender's IntProperty is a signed 32-bit integer.
_INT_MAX = 2**31 - 1

# How Blender shows a setting, beyond the table: label ("name"), slider end, digits. All optional.
PRESENTATION = {
    "photons": dict(soft_max=10_000_000),
    "radius": dict(soft_max=1.0, precision=4),
    "max_bounces": dict(soft_max=32),
    "direct_samples": dict(soft_max=64),
    "normal_tolerance": dict(name="Normal Tolerance (degrees)"),
    "directional_level": dict(soft_max=16),
    "memory_budget": dict(name="Memory Budget (GiB)", soft_max=256.0, precision=1),
    "aimed_photons": dict(soft_max=1.0),
    "iterations": dict(soft_max=1000),
    "time_limit": dict(soft_max=600.0),
    "threads": dict(soft_max=256),
}

# Labels and tooltips of the choices of enumerations; a choice missing here is shown by its name.
CHOICES = {
    "method": {
        "cluster_cone": ("Cluster + Cones", "The paper's cluster-trivial: the cluster hierarchy with normal-cone "
                                            "trivial reject and accept; exact"),
        "cluster": ("Cluster", "Photons walk a hierarchy of view-sample clusters, culled by bounding boxes; exact"),
        "directional": ("Directional (approximate)",
                        "Flux gathered per cluster of one level in 8 direction bins: faster, approximate"),
        "tiled": ("Tiled", "Mara et al. 2013: photons binned into 32x32-pixel screen tiles with depth bounds; exact"),
        "gather": ("Gather", "Each pixel gathers photons from a hashed uniform grid; exact"),
        "brute": ("Brute Force",
                  "Every photon against every view sample; exact but slow, meant as a reference for small images"),
    },
    "kernel": {
        "uniform": ("Uniform", "Constant weight inside the radius (keeps the cone method's trivial accept exact)"),
        "epanechnikov": ("Epanechnikov", "Weight falling off as 1 - d^2/r^2: smoother photon footprints"),
    },
}

_KINDS = {"uint": "int", "int": "int", "float": "float", "double": "float", "bool": "bool", "enum": "enum"}
_UNITS = {"length": "LENGTH", "seconds": "TIME_ABSOLUTE"}


def stored(settings=None):
    """The rows of the table that scene.photonsplat stores."""
    return tuple(row for row in (SETTINGS if settings is None else settings) if row["name"] not in FROM_BLENDER)


def label(name):
    return PRESENTATION.get(name, {}).get("name") or name.replace("_", " ").title()


def _kind(row):
    """'int', 'float', 'bool' or 'enum': the kind of Blender property (bytes are shown as GiB, a float)."""
    return "float" if row["unit"] == "bytes" else _KINDS[row["type"]]


def _scale(row):
    return 1.0 / GIB if row["unit"] == "bytes" else 1.0


def _limits(row):
    """min / max of the Blender property: the table's range in Blender's units and integer width. Blender has no
    open bounds: an open one becomes the nearest value inside (the core names the setting if that is still out)."""
    kind, scale, limits = _kind(row), _scale(row), {}
    for key, exclusive, step in (("min", row["min_exclusive"], 1), ("max", row["max_exclusive"], -1)):
        bound = row[key]
        if bound is None or kind not in ("int", "float"):
            continue
        if kind == "int":
            bound = max(-_INT_MAX - 1, min(_INT_MAX, bound + step if exclusive else bound))
        else:
            bound = bound * scale
            if exclusive:
                bound += step * max(abs(bound), 1.0) * 1e-6
        limits[key] = bound
    return limits


def _forward(name):
    """get and set functions of a property that stands for `name` (Blender wants exactly 1 and 2 parameters)."""
    def get(props):
        return getattr(props, name)

    def set(props, value):
        setattr(props, name, value)

    return get, set


def property_specs(settings=None):
    """[(name, kind, keyword arguments)] for Blender: kind is 'int', 'float', 'bool' or 'enum' (IntProperty, ...),
    one per stored setting in the table's order, then one per deprecated alias, which reads and writes the
    setting under its new name (its description says so)."""
    specs, aliases = [], []
    for row in stored(settings):
        name, kind, shown = row["name"], _kind(row), dict(PRESENTATION.get(row["name"], {}))
        shown.pop("name", None)
        kwargs = dict(name=label(name), description=row["description"], **_limits(row), **shown)
        if kind == "enum":
            labels = CHOICES.get(name, {})
            kwargs["items"] = tuple((c, *labels.get(c, (c.replace("_", " ").title(), ""))) for c in row["choices"])
        if kind == "float":
            kwargs["default"] = row["default"] * _scale(row)
            if row["unit"] in _UNITS:
                kwargs["unit"] = _UNITS[row["unit"]]
        else:
            kwargs["default"] = row["default"]
        specs.append((name, kind, kwargs))
        for alias in row["aliases"]:
            alias_kwargs = {k: v for k, v in kwargs.items() if k != "default"}
            alias_kwargs["description"] = f"Deprecated: the old name of {label(name)} ('{name}'), kept for scripts " \
                                          f"and older files. {row['description']}"
            alias_kwargs["get"], alias_kwargs["set"] = _forward(name)
            aliases.append((alias, kind, alias_kwargs))
    return specs + aliases


def renamed(settings=None):
    """{deprecated name: setting}: the names older versions stored."""
    return {alias: row["name"] for row in stored(settings) for alias in row["aliases"]}


def render_settings_kwargs(props, settings=None):
    """scene.photonsplat (or anything with its attributes) -> the keyword arguments of RenderSettings: every
    setting of the table it stores, in the core's units. The settings Blender keeps elsewhere (FROM_BLENDER)
    are the caller's to add."""
    kwargs = {}
    for row in stored(settings):
        value, kind = getattr(props, row["name"]), _kind(row)
        if row["unit"] == "bytes":
            value = int(value * GIB)
        elif kind == "int":
            value = int(value)
        elif kind == "float":
            value = float(value)
        elif kind == "bool":
            value = bool(value)
        else:
            value = str(value)
        kwargs[row["name"]] = value
    return kwargs
