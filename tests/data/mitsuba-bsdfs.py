#!/usr/bin/env python3
"""Writes tests/data/mitsuba-bsdfs.tsv: Mitsuba 3's own BSDF values, for tests/mitsuba_bsdfs.rs.

Each Mitsuba BSDF that photonwave renders as Mitsuba does is loaded through Mitsuba's Python API
(`pip install mitsuba`, variant scalar_rgb) with a grid of parameters, and evaluated over pairs of
directions in the local frame (normal +z): f (Mitsuba's `eval` divided by the cosine it includes)
and the pdf of its `sample`; for the delta lobes (smooth conductor, thin dielectric), a sample's direction, weight and lobe probability. Mitsuba's wi (toward the viewer) is photonwave's wo, and Mitsuba's wo
photonwave's wi; the table uses photonwave's names.

Not needed to build or test: the table is checked in. Run it again when a BSDF or its parameter
grid changes:  python3 tests/data/mitsuba-bsdfs.py
"""
import math
import os

import mitsuba as mi

mi.set_variant("scalar_rgb")

KD = [0.8, 0.5, 0.2]


def configs():
    """(name, photonwave parameters, Mitsuba dictionary) for every BSDF in the table."""
    yield "diffuse", {"kd": KD}, {"type": "diffuse", "reflectance": {"type": "rgb", "value": KD}}
    for alpha in [0.05, 0.2, 0.6]:
        yield (
            "roughconductor",
            {"alpha": alpha},
            {"type": "roughconductor", "distribution": "ggx", "alpha": alpha, "material": "none"},
        )
    # Named metals (Mitsuba's own complex indices) and an explicit η, k with a colour scale.
    for alpha, metal in [(0.1, "Cu"), (0.3, "Au")]:
        yield (
            "roughconductor",
            {"alpha": alpha, "metal": metal},
            {"type": "roughconductor", "distribution": "ggx", "alpha": alpha, "material": metal},
        )
    yield (
        "roughconductor",
        {"alpha": 0.2, "eta": [0.2, 0.9, 1.1], "k": [3.9, 2.4, 2.1], "ks": [0.9, 0.8, 0.7]},
        {
            "type": "roughconductor",
            "distribution": "ggx",
            "alpha": 0.2,
            "eta": {"type": "rgb", "value": [0.2, 0.9, 1.1]},
            "k": {"type": "rgb", "value": [3.9, 2.4, 2.1]},
            "specular_reflectance": {"type": "rgb", "value": [0.9, 0.8, 0.7]},
        },
    )
    for alpha in [0.1, 0.4]:
        yield (
            "roughdielectric",
            {"alpha": alpha, "ior": 1.5},
            {"type": "roughdielectric", "distribution": "ggx", "alpha": alpha, "int_ior": 1.5, "ext_ior": 1.0},
        )
    for alpha in [0.01, 0.1, 0.3]:
        for nonlinear in [False, True]:
            yield (
                "roughplastic",
                {"alpha": alpha, "ior": 1.5, "kd": KD, "nonlinear": nonlinear, "ks": [1.0, 1.0, 1.0]},
                {
                    "type": "roughplastic",
                    "distribution": "ggx",
                    "alpha": alpha,
                    "int_ior": 1.5,
                    "ext_ior": 1.0,
                    "nonlinear": nonlinear,
                    "diffuse_reflectance": {"type": "rgb", "value": KD},
                },
            )



def distributions():
    """Beckmann (Mitsuba's default distribution) for each rough BSDF, and anisotropic widths of
    both distributions for the conductor and the dielectric (x and y along the frame's s and t,
    which for the normal +z both sides build as the world's x and y)."""
    for alpha in [0.05, 0.2, 0.6]:
        yield (
            "roughconductor",
            {"alpha": alpha, "distribution": "beckmann"},
            {"type": "roughconductor", "distribution": "beckmann", "alpha": alpha, "material": "none"},
        )
    yield (
        "roughconductor",
        {"alpha": 0.1, "distribution": "beckmann", "metal": "Cu"},
        {"type": "roughconductor", "distribution": "beckmann", "alpha": 0.1, "material": "Cu"},
    )
    for dist, (u, v) in [("ggx", (0.05, 0.3)), ("beckmann", (0.3, 0.1))]:
        yield (
            "roughconductor",
            {"alpha": (u * v) ** 0.5, "distribution": dist, "alpha_u": u, "alpha_v": v},
            {"type": "roughconductor", "distribution": dist, "alpha_u": u, "alpha_v": v, "material": "none"},
        )
    for alpha in [0.1, 0.4]:
        yield (
            "roughdielectric",
            {"alpha": alpha, "ior": 1.5, "distribution": "beckmann"},
            {"type": "roughdielectric", "distribution": "beckmann", "alpha": alpha, "int_ior": 1.5, "ext_ior": 1.0},
        )
    for dist, (u, v) in [("ggx", (0.1, 0.3)), ("beckmann", (0.2, 0.05))]:
        yield (
            "roughdielectric",
            {"alpha": (u * v) ** 0.5, "ior": 1.5, "distribution": dist, "alpha_u": u, "alpha_v": v},
            {
                "type": "roughdielectric",
                "distribution": dist,
                "alpha_u": u,
                "alpha_v": v,
                "int_ior": 1.5,
                "ext_ior": 1.0,
            },
        )
    for alpha in [0.1, 0.3]:
        for nonlinear in [False, True]:
            yield (
                "roughplastic",
                {"alpha": alpha, "ior": 1.5, "kd": KD, "nonlinear": nonlinear, "ks": [1.0, 1.0, 1.0], "distribution": "beckmann"},
                {
                    "type": "roughplastic",
                    "distribution": "beckmann",
                    "alpha": alpha,
                    "int_ior": 1.5,
                    "ext_ior": 1.0,
                    "nonlinear": nonlinear,
                    "diffuse_reflectance": {"type": "rgb", "value": KD},
                },
            )


def smooth_plastic():
    """The smooth plastic: its base's f and pdf (eval, pdf), and its coat's sample."""
    for nonlinear in [False, True]:
        yield (
            "plastic",
            {"ior": 1.5, "kd": KD, "nonlinear": nonlinear, "ks": [1.0, 1.0, 1.0]},
            {
                "type": "plastic",
                "int_ior": 1.5,
                "ext_ior": 1.0,
                "nonlinear": nonlinear,
                "diffuse_reflectance": {"type": "rgb", "value": KD},
            },
        )
    ks = [0.9, 0.6, 0.3]
    yield (
        "plastic",
        {"ior": 1.33, "kd": KD, "nonlinear": False, "ks": ks},
        {
            "type": "plastic",
            "int_ior": 1.33,
            "ext_ior": 1.0,
            "diffuse_reflectance": {"type": "rgb", "value": KD},
            "specular_reflectance": {"type": "rgb", "value": ks},
        },
    )


def smooth():
    """The smooth conductor: its sample's weight is its Fresnel reflectance."""
    for metal in ["none", "Ag", "Al", "Au", "Cr", "Cu", "W"]:
        yield "conductor", {"metal": metal}, {"type": "conductor", "material": metal}
    yield "thindielectric", {"ior": 1.5}, {"type": "thindielectric", "int_ior": 1.5, "ext_ior": 1.0}


def scaled():
    """A rough plastic whose coat is scaled by `specular_reflectance`; dielectrics scaled by
    `specular_reflectance` and `specular_transmittance`."""
    rt, tt = [0.9, 0.7, 0.5], [0.6, 0.8, 1.0]
    scales = {"specular_reflectance": {"type": "rgb", "value": rt}, "specular_transmittance": {"type": "rgb", "value": tt}}
    yield (
        "roughdielectric",
        {"alpha": 0.2, "ior": 1.5, "rt": rt, "tt": tt},
        dict({"type": "roughdielectric", "distribution": "ggx", "alpha": 0.2, "int_ior": 1.5, "ext_ior": 1.0}, **scales),
    )
    yield "thindielectric", {"ior": 1.5, "rt": rt, "tt": tt}, dict({"type": "thindielectric", "int_ior": 1.5, "ext_ior": 1.0}, **scales)
    yield "dielectric", {"ior": 1.5, "rt": rt, "tt": tt}, dict({"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0}, **scales)
    yield "dielectric", {"ior": 1.33}, {"type": "dielectric", "int_ior": 1.33, "ext_ior": 1.0}
    ks = [0.9, 0.6, 0.3]
    yield (
        "roughplastic",
        {"alpha": 0.1, "ior": 1.5, "kd": KD, "nonlinear": False, "ks": ks},
        {
            "type": "roughplastic",
            "distribution": "ggx",
            "alpha": 0.1,
            "int_ior": 1.5,
            "ext_ior": 1.0,
            "diffuse_reflectance": {"type": "rgb", "value": KD},
            "specular_reflectance": {"type": "rgb", "value": ks},
        },
    )


def direction(theta_deg, phi_deg):
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return [math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)]


def pairs(alpha, transmits):
    """(wo, wi) pairs: a coarse grid over both hemispheres' angles, and directions near the
    mirror (and, for a dielectric, the refracted) direction at a few multiples of alpha."""
    out = []
    for to in [0.0, 30.0, 60.0, 80.0]:
        wo = direction(to, 10.0)
        for ti in [5.0, 25.0, 45.0, 65.0, 85.0]:
            for pi_ in [10.0, 100.0, 190.0]:
                out.append((wo, direction(ti, pi_)))
                if transmits:
                    out.append((wo, direction(180.0 - ti, pi_)))
        for k in [0.25, 1.0, 2.0]:
            spread = math.degrees(k * alpha)
            for ti in [to - spread, to + spread]:
                out.append((wo, direction(abs(ti), 190.0 if ti >= 0 else 10.0)))
        # Seen from inside a dielectric.
        if transmits:
            wo_in = direction(180.0 - to, 10.0)
            for ti in [5.0, 25.0, 45.0, 65.0]:
                for pi_ in [10.0, 190.0]:
                    out.append((wo_in, direction(ti, pi_)))
                    out.append((wo_in, direction(180.0 - ti, pi_)))
    return out


def main():
    ctx = mi.BSDFContext()
    si = mi.SurfaceInteraction3f()
    si.n = mi.Normal3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    si.uv = mi.Point2f(0.5, 0.5)
    rows = []
    for name, ours, theirs in list(configs()) + list(scaled()) + list(distributions()) + list(smooth()) + list(smooth_plastic()):
        bsdf = mi.load_dict(theirs)
        params = ";".join(f"{k}={','.join(map(str, v)) if isinstance(v, list) else v}" for k, v in ours.items())
        if name == "plastic":
            # The base: f and pdf over direction pairs. The coat: a sample with sample1 = 0 (the
            # coat whenever its probability is above 0) records the mirror direction, the
            # weight (F·ks over the probability) and the probability, under the name
            # "plastic-coat".
            for wo, wi in pairs(0.0, False):
                si.wi = mi.Vector3f(wo)
                value = bsdf.eval(ctx, si, mi.Vector3f(wi))
                pdf = bsdf.pdf(ctx, si, mi.Vector3f(wi))
                f = [float(value[c]) / abs(wi[2]) for c in range(3)]
                rows.append([name, params] + [f"{x:.9g}" for x in wo + wi + f] + [f"{float(pdf):.9g}"])
            for theta in [0.0, 30.0, 60.0, 80.0, 89.0]:
                wo = direction(theta, 10.0)
                si.wi = mi.Vector3f(wo)
                bs, weight = bsdf.sample(ctx, si, 0.0, mi.Point2f(0.5, 0.5))
                wi = [float(bs.wo[c]) for c in range(3)]
                f = [float(weight[c]) for c in range(3)]
                rows.append(["plastic-coat", params] + [f"{x:.9g}" for x in wo + wi + f] + [f"{float(bs.pdf):.9g}"])
            continue
        if name in ("conductor", "thindielectric", "dielectric"):
            # Delta lobes: a sample's direction and weight (f·cos/pdf) in f, and the probability
            # of the lobe it chose in pdf (1 for the mirror); the thin sheet's reflection
            # (sample1 = 0) and transmission (sample1 just below 1), from either side.
            choices = [0.5] if name == "conductor" else [0.0, 0.99999]
            for theta in [0.0, 30.0, 60.0, 80.0, 89.0, 120.0, 170.0]:
                if name == "conductor" and theta > 90.0:
                    continue
                wo = direction(theta, 10.0)
                si.wi = mi.Vector3f(wo)
                for u in choices:
                    bs, weight = bsdf.sample(ctx, si, u, mi.Point2f(0.5, 0.5))
                    wi = [float(bs.wo[c]) for c in range(3)]
                    f = [float(weight[c]) for c in range(3)]
                    rows.append([name, params] + [f"{x:.9g}" for x in wo + wi + f] + [f"{float(bs.pdf):.9g}"])
            continue
        for wo, wi in pairs(ours.get("alpha", 0.0), name == "roughdielectric"):
            si.wi = mi.Vector3f(wo)
            value = bsdf.eval(ctx, si, mi.Vector3f(wi))
            pdf = bsdf.pdf(ctx, si, mi.Vector3f(wi))
            cos = abs(wi[2])
            f = [float(value[c]) / cos for c in range(3)]
            rows.append([name, params] + [f"{x:.9g}" for x in wo + wi + f] + [f"{float(pdf):.9g}"])
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "mitsuba-bsdfs.tsv")
    with open(path, "w") as out:
        out.write(f"# Mitsuba {mi.__version__} (scalar_rgb): f and pdf; written by mitsuba-bsdfs.py\n")
        out.write("bsdf\tparams\two_x\two_y\two_z\twi_x\twi_y\twi_z\tf_r\tf_g\tf_b\tpdf\n")
        for r in rows:
            out.write("\t".join(r) + "\n")
    print(f"{len(rows)} rows to {path}")


if __name__ == "__main__":
    main()
