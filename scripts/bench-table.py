#!/usr/bin/env python3
"""The table scripts/bench writes into docs/performance.md: glray and the anchors side by side
per mesh, with ratios (above 1: glray is faster or smaller).
usage: bench-table.py RESULTS_DIR N [N...]"""
import json
import sys


def results(path):
    """RESULT and RUNINFO lines as (kind, what, {key: value}); none if the file is missing."""
    out = []
    try:
        lines = open(path, errors="replace").readlines()
    except FileNotFoundError:
        return out
    for line in lines:
        words = line.split()
        if words and words[0] in ("RESULT", "RUNINFO"):
            what = words[1] if words[0] == "RESULT" else "info"
            fields = dict(w.split("=", 1) for w in words[1:] if "=" in w)
            out.append((words[0], what, fields))
    return out


def pick(rows, what, **match):
    for kind, w, f in rows:
        if w == what and all(f.get(k) == v for k, v in match.items()):
            return f
    return {}


def num(d, key):
    try:
        return float(d[key])
    except (KeyError, ValueError):
        return float("nan")


def ratio(theirs, ours):
    return f"{theirs / ours:.2f}x" if ours and ours == ours and theirs == theirs else "-"


def main():
    d, ns = sys.argv[1], sys.argv[2:]
    print("| mesh | measure | glray | anchor | anchor / glray |")
    print("|---|---|---:|---:|---:|")
    for n in ns:
        g = json.load(open(f"{d}/mesh_{n}.glray.json"))
        e = results(f"{d}/mesh_{n}.embree.txt")
        tris = g["triangles"]
        name = f"{tris / 1e6:.1f}M" if tris >= 1e6 else f"{tris / 1e3:.0f}K"
        build = pick(e, "build")
        single = pick(e, "primary", mode="single", threads="2")
        pkt16 = pick(e, "primary", mode="pkt16", threads="2")
        ao1 = pick(e, "ao", mode="ao1", threads="2")
        info = pick(e, "info")
        # Embree's low build (Morton codes): the quickest tree to build, and slower to trace;
        # the bar for glray's tracing beside a build no slower than Embree's medium.
        low = results(f"{d}/mesh_{n}.embree-low.txt")
        low_single = pick(low, "primary", mode="single", threads="2")
        low_ao1 = pick(low, "ao", mode="ao1", threads="2")
        rows = [
            ("BVH build, s (Embree medium)", g["build_s_min"], num(build, "min_s")),
            ("primary rays, ms per frame (Embree single rays)", g["primary_ms_min"], num(single, "frame_ms_min")),
            ("primary rays, ms per frame (Embree 16-wide packets)", g["primary_ms_min"], num(pkt16, "frame_ms_min")),
            ("AO, 16 rays/hit, ms per pass (Embree rtcOccluded1)", g["ao_ms_min"], num(ao1, "ao_pass_ms_min")),
            ("BVH build, s (Embree low)", g["build_s_min"], num(pick(low, "build"), "min_s")),
            ("primary rays, ms per frame (Embree low tree, single rays)", g["primary_ms_min"],
             num(low_single, "frame_ms_min")),
            ("AO, 16 rays/hit, ms per pass (Embree low tree, rtcOccluded1)", g["ao_ms_min"],
             num(low_ao1, "ao_pass_ms_min")),
            ("peak memory, MB (Embree medium)", g["peak_mb"], num(info, "maxrss_kb") / 1024),
        ]
        # glray's fast build (a linear BVH, `bvh=fast`) beside Embree's low one (a Morton build).
        try:
            f = json.load(open(f"{d}/mesh_{n}.glray-fast.json"))
        except FileNotFoundError:
            f = {}
        fast = lambda key: f.get(key, float("nan"))
        rows += [
            ("BVH build, s, glray fast (Embree low)", fast("build_s_min"), num(pick(low, "build"), "min_s")),
            ("primary rays, ms per frame, glray fast tree (Embree low tree, single rays)", fast("primary_ms_min"),
             num(low_single, "frame_ms_min")),
            ("AO, 16 rays/hit, ms per pass, glray fast tree (Embree low tree, rtcOccluded1)", fast("ao_ms_min"),
             num(low_ao1, "ao_pass_ms_min")),
        ]
        rows += [
            ("GL-look frame, ms (shaded; no anchor)", g["frame_ms_min"], float("nan")),
            ("GL look x AO frame, ms (shaded; no anchor)", g["ao_frame_ms_min"], float("nan")),
        ]
        for m in ("dl", "vbo", "va"):
            ll = pick(results(f"{d}/mesh_{n}.osmesa-{m}.txt"), "osmesa")
            gr = pick(results(f"{d}/mesh_{n}.glray-osmesa-{m}.txt"), "osmesa")
            rows.append((f"osmesa_bench {m} frame, ms (llvmpipe; glray: same program, every frame ray traced)",
                         num(gr, "frame_ms_median"), num(ll, "frame_ms_median")))
        for m in ("dl", "vbo", "va"):
            # osmesa_bench draws one scene over and over: under glray's defaults each frame
            # after the first shows the traced picture again (capture, compare, present).
            ll = pick(results(f"{d}/mesh_{n}.osmesa-{m}.txt"), "osmesa")
            gr = pick(results(f"{d}/mesh_{n}.glray-osmesa-reused-{m}.txt"), "osmesa")
            rows.append((f"osmesa_bench {m} frame, ms (llvmpipe; glray as a user runs it: unchanged frames shown again)",
                         num(gr, "frame_ms_median"), num(ll, "frame_ms_median")))
        # A new mesh every frame (time steps): under glray's defaults the last step's tree is
        # refitted to it (the same triangles, moved by `deform` or not at all).
        for kind, how in (("", "the same mesh sent again"), ("-deform", "its vertices moved")):
            ll = pick(results(f"{d}/mesh_{n}.steps{kind}.txt"), "steps")
            gr = pick(results(f"{d}/mesh_{n}.glray-steps{kind}.txt"), "steps")
            rows.append((f"steps_bench frame, ms (llvmpipe; glray: a new mesh every frame, as time steps: {how})",
                         num(gr, "frame_ms_median"), num(ll, "frame_ms_median")))
        for what, ours, theirs in rows:
            anchor = f"{theirs:.3g}" if theirs == theirs else "-"
            print(f"| {name} | {what} | {ours:.3g} | {anchor} | {ratio(theirs, ours)} |")
    print()
    print(f"Hits (pixels on the surface): glray {g['hits']}; {g['threads']} threads; "
          "ratios above 1 mean glray is faster (or smaller).")


main()
