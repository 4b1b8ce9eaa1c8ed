"""Geometry helpers for the Blender tests: where the glass sphere's caustic lands, and which image pixels
show a given world point. Plain numpy, so it also runs (and can be checked) outside Blender."""

import math

import numpy as np


def _refract(d, n, eta):
    """Refract unit directions d (k, 3) at unit normals n facing against d; eta = n_from / n_to.
    Returns (directions, ok) where ok is False on total internal reflection."""
    cos_i = -np.sum(d * n, axis=1)
    sin2_t = eta * eta * (1.0 - cos_i * cos_i)
    ok = sin2_t <= 1.0
    cos_t = np.sqrt(np.clip(1.0 - sin2_t, 0.0, None))
    out = eta * d + (eta * cos_i - cos_t)[:, None] * n
    return out / np.linalg.norm(out, axis=1, keepdims=True), ok


def _sphere_hits(origins, dirs, center, radius):
    """Distances t (near, far) along unit rays to a sphere; NaN where missed."""
    oc = origins - center
    b = np.sum(oc * dirs, axis=1)
    c = np.sum(oc * oc, axis=1) - radius * radius
    disc = b * b - c
    root = np.sqrt(np.where(disc >= 0.0, disc, np.nan))
    return -b - root, -b + root


def caustic_floor_points(light, center, radius, ior, floor_z=0.0, count=4000, seed=1):
    """Points where light from a point source, refracted through a glass sphere (in and out), meets the
    floor plane z = floor_z. Rays are spread uniformly over the sphere's silhouette as seen from the light."""
    light, center = np.asarray(light, float), np.asarray(center, float)
    rng = np.random.default_rng(seed)
    axis = center - light
    dist = np.linalg.norm(axis)
    axis /= dist
    cos_max = np.sqrt(1.0 - (radius / dist) ** 2)
    cos_t = 1.0 - rng.random(count) * (1.0 - cos_max)          # uniform over the cone's solid angle
    phi = 2.0 * np.pi * rng.random(count)
    sin_t = np.sqrt(1.0 - cos_t * cos_t)
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(axis, helper)
    u /= np.linalg.norm(u)
    v = np.cross(axis, u)
    dirs = (cos_t[:, None] * axis + (sin_t * np.cos(phi))[:, None] * u + (sin_t * np.sin(phi))[:, None] * v)
    origins = np.repeat(light[None, :], count, axis=0)

    t_in, _ = _sphere_hits(origins, dirs, center, radius)
    keep = np.isfinite(t_in)
    p1 = origins[keep] + t_in[keep, None] * dirs[keep]
    n1 = (p1 - center) / radius
    d1, ok1 = _refract(dirs[keep], n1, 1.0 / ior)
    _, t_out = _sphere_hits(p1, d1, center, radius)
    p2 = p1 + t_out[:, None] * d1
    n2 = (center - p2) / radius                                   # inner normal, facing against d1
    d2, ok2 = _refract(d1, n2, ior)
    ok = ok1 & ok2 & (d2[:, 2] < 0.0)
    p2, d2 = p2[ok], d2[ok]
    t_floor = (floor_z - p2[:, 2]) / d2[:, 2]
    return p2 + t_floor[:, None] * d2


def floor_ring(landing, eye, spheres):
    """Floor points on two rings around the middle of the caustic's `landing` points, inside the box (|x|, |y| <
    0.95), away from both (center, radius) spheres and seen from `eye`: the caustic's surroundings."""
    focus = np.median(landing, axis=0)
    ring = [focus + r * np.array([math.cos(a), math.sin(a), 0.0])
            for r in (0.35, 0.45) for a in np.linspace(0.0, 2.0 * math.pi, 48, endpoint=False)]
    ring = np.array([p for p in ring if abs(p[0]) < 0.95 and abs(p[1]) < 0.95 and all(
        np.linalg.norm(p[:2] - np.asarray(c)[:2]) > 1.2 * r for c, r in spheres)])
    return ring[visible_from(ring, eye, spheres)]


def visible_from(points, eye, spheres):
    """Mask of points whose straight line to `eye` misses every (center, radius) sphere."""
    points = np.asarray(points, float)
    eye = np.asarray(eye, float)
    to_eye = eye - points
    length = np.linalg.norm(to_eye, axis=1)
    dirs = to_eye / length[:, None]
    visible = np.ones(len(points), dtype=bool)
    for center, radius in spheres:
        t0, t1 = _sphere_hits(points + 1e-4 * dirs, dirs, np.asarray(center, float), radius)
        blocked = np.isfinite(t0) & (t1 > 0.0) & (t0 < length)
        visible &= ~blocked
    return visible
