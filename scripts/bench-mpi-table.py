#!/usr/bin/env python3
"""The tables of scripts/bench-mpi (docs/distributed.md keeps them), from its run directory:
frame times the hosts printed (NAME.times), glray's statistics (NAME.jsonl), CPU seconds
(NAME.cpu), the links measured (link-RATE.link), glray bench's ceiling runs (*.json).
Also writes measured.json there: the terms scripts/model-mpi takes."""
import json, pathlib, statistics, sys

out, w, h, repeats, frames = pathlib.Path(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
med = statistics.median


def times(name):
    t = [float(l.split(":")[2].split()[0]) for l in (out / f"{name}.times").read_text().splitlines()]
    return t[0], med(t[1:]) if len(t) > 1 else t[0]


def stats(name):
    return [json.loads(l) for l in (out / f"{name}.jsonl").read_text().splitlines() if l.strip()]


def rank0(name, steady=True):
    """Rank 0's statistics lines (one a frame; the first frame left out when steady)."""
    rows = [r for r in stats(name) if r.get("rank", 0) == 0 and r.get("thread", 0) == 0]
    return [r for r in rows if r["frame"] > 0] if steady else [r for r in rows if r["frame"] == 0]


def per_pixel(rows, field):
    px = sum(r.get("pixels_elsewhere", 0) for r in rows)
    return sum(r.get(field, 0) for r in rows) / px if px else 0.0


def cpu(name):
    user, system = (float(x) for x in (out / f"{name}.cpu").read_text().split()[-2:])
    return user + system


measured = {"width": w, "height": h}
print(f"AO (16 rays), 1M-triangle isosurface (examples/mpi/icet_like.c), {w}x{h}, every frame traced anew, TCP on loopback\n")
print("| ranks x threads | first frame (s) | steady frame (s) | speed-up over 1 rank | rank 0's MPI wait | imbalance | rank 0 receives, bytes a pixel traced elsewhere (raw) | sent, first frame |")
print("|---|---|---|---|---|---|---|---|")
f0, fs = times("local-1x1")
print(f"| no MPI (local) x 1 | {f0:.2f} | {fs:.2f} | - | - | - | - | - |")
one = times("ranks-1x1")[1]
for np in [1, 2, 3, 4]:
    name = f"ranks-{np}x1"
    f0, fs = times(name)
    steady = rank0(name)
    every = stats(name)
    wait = med([r.get("wait_ms", 0) for r in steady]) / 1e3 if steady else 0
    imb = [r["imbalance"] for r in steady if r.get("imbalance") is not None]
    first_sent = sum(r.get("bytes_sent", 0) for r in every if r["frame"] == 0 and "rank" in r)
    got = f"{per_pixel(steady, 'bytes_received'):.1f} ({per_pixel(steady, 'raw_received'):.1f})" if np > 1 else "-"
    print(f"| {np} x 1 | {f0:.2f} | {fs:.2f} | {one / fs:.2f}x | {wait / fs:.1%} | {med(imb) if imb else 1.0:.2f} | {got} | {first_sent / 2**20:.1f} MiB |")

print("\n2 ranks x 1 thread over 1 rank x 1 thread, alternated pairs (steady frames):\n")
print("| host | pairs | median |")
print("|---|---|---|")
for label, stem in [("icet_like (1M isosurface, OSMesa)", "pair"), ("direct_send (tori, cones, spheres, GLX, camera circling)", "direct")]:
    ratios = [times(f"{stem}-{k}-1x1")[1] / times(f"{stem}-{k}-2x1")[1] for k in range(1, repeats + 1)]
    measured[f"speedup_{stem}"] = med(ratios)
    print(f"| {label} | {', '.join(f'{r:.2f}x' for r in ratios)} | {med(ratios):.2f}x |")

print("\nRank 0's stages a frame (ms, medians of steady frames; icet_like, AO):\n")
stages = [("capture", "capture_ms"), ("BVH builds", "build_ms"), ("its own tiles (tracing)", "rank_trace_ms"),
          ("waiting for rows of its band", "band_wait_ms"), ("its band: adding up, denoising", "band_ms"),
          ("present", "present_ms"), ("waiting on MPI, all told", "wait_ms")]
print("| stage | 1 rank | 2 ranks | 3 ranks | 4 ranks |")
print("|---|---|---|---|---|")
for label, field in stages:
    cells = [f"{med([r.get(field, 0) for r in rank0(f'ranks-{np}x1')]):.1f}" for np in [1, 2, 3, 4]]
    print(f"| {label} | {' | '.join(cells)} |")
cells = [f"{times(f'ranks-{np}x1')[1] * 1e3:.0f}" for np in [1, 2, 3, 4]]
print(f"| the frame, as the host times it | {' | '.join(cells)} |")

two = rank0("ranks-2x1")
measured["present_ms"] = med([r["present_ms"] for r in two])
measured["band_ms_2"] = med([r["band_ms"] for r in two])
measured["trace_ms_1"] = med([r["rank_trace_ms"] for r in rank0("ranks-1x1")])
measured["tiles_total"] = med([r["tiles_total"] for r in two])
measured["received_per_pixel"] = per_pixel(two, "bytes_received")
measured["raw_per_pixel"] = per_pixel(two, "raw_received")
gl = rank0("gl-2x1")
measured["gl_received_per_pixel"] = per_pixel(gl, "bytes_received")
measured["gl_raw_per_pixel"] = per_pixel(gl, "raw_received")
for np in [1, 2, 3, 4]:
    measured[f"frame_{np}"] = times(f"ranks-{np}x1")[1]
one_rank = rank0("ranks-1x1")
measured["band_ms_1"] = med([r["band_ms"] for r in one_rank])
measured["capture_ms"] = med([r["capture_ms"] for r in one_rank])
measured["mrays_per_s_core"] = med([r["rays"] / r["rank_trace_ms"] / 1e3 for r in one_rank])
# Each rank's tracing speed with 2 ranks on the node (every rank's steady frames).
measured["mrays_per_s_core_2"] = med([r["rays"] / r["rank_trace_ms"] / 1e3 for r in stats("ranks-2x1")
                                      if r["frame"] > 0 and "rank" in r])
every_two = [r for r in stats("ranks-2x1") if r["frame"] > 0 and "rank" in r]
unpacked = sum(r.get("unpack_ms", 0) for r in every_two)
packed = sum(r.get("pack_ms", 0) for r in every_two)
measured["unpack_gb_s"] = sum(r["raw_received"] for r in every_two) / unpacked / 1e6 if unpacked else None
measured["pack_gb_s"] = sum(r["raw_sent"] for r in every_two) / packed / 1e6 if packed else None

print("\nCompression (mpi_compression), 2 ranks x 1 thread:\n")
print("| link | compression | steady frame (s) | rank 0 receives, bytes a pixel | raw | ratio | first frame (s) |")
print("|---|---|---|---|---|---|---|")
for link, names in [("loopback", [("lz4", "ranks-2x1"), ("zstd", "compression-zstd"), ("none", "compression-none")]),
                    ("1 Gbit/s (namespace hosts)", [("lz4", "hosts-1gbit"), ("zstd", "hosts-1gbit-zstd"), ("none", "hosts-1gbit-none")])]:
    for c, name in names:
        rows = rank0(name)
        got, raw = per_pixel(rows, "bytes_received"), per_pixel(rows, "raw_received")
        f0, fs = times(name)
        print(f"| {link} | {c} | {fs:.2f} | {got:.1f} | {raw:.1f} | {raw / got if got else 0:.1f}x | {f0:.2f} |")

print("\nglray's MPI thread waiting 1 ms between looks (mpi_poll=1000, the default) or never (0), 2 ranks x 1 thread:\n")
print("| mpi_poll | steady frame (s) | CPU seconds of the job a frame |")
print("|---|---|---|")
for label, name in [("1000 (1 ms)", "ranks-2x1"), ("0 (spinning)", "poll-0")]:
    print(f"| {label} | {times(name)[1]:.2f} | {cpu(name) / frames:.2f} |")

print("\n2 ranks on 2 hosts in network namespaces (scripts/lib/netns-hosts), their links shaped with tc:\n")
print("| link | round trip (us) | TCP stream (Gbit/s) | AO steady frame (s) | AO first frame (s) | 10M triangles: scene exchange (s), sent |")
print("|---|---|---|---|---|---|")
for rate, label in [("none", "veth as it is"), ("10gbit", "10 Gbit/s"), ("1gbit", "1 Gbit/s")]:
    rtt, gbit = (float(x) for x in (out / f"link-{rate}.link").read_text().split())
    f0, fs = times(f"hosts-{rate}")
    first = [r for r in stats(f"hosts-{rate}-10M-gl") if r["frame"] == 0 and "rank" in r]
    ex = max(r["exchange_ms"] for r in first) / 1e3
    sent = sum(r["bytes_sent"] for r in first)
    measured[f"link_{rate}"] = {"rtt_us": rtt, "gbit": gbit, "frame": fs}
    print(f"| {label} | {rtt:.0f} | {gbit:.2f} | {fs:.2f} | {f0:.2f} | {ex:.2f}, {sent / 2**20:.0f} MiB |")

first = [r for r in stats("ranks-2x1-10M-gl") if r["frame"] == 0 and "rank" in r]
print(f"\nreplication on loopback, 10M triangles over 2 ranks: the first frame's scene exchange "
      f"{max(r['exchange_ms'] for r in first) / 1e3:.2f} s, {sum(r['bytes_sent'] for r in first) / 2**20:.0f} MiB sent")


def ao(name):
    return json.loads((out / name).read_text())["ao_frame_ms_median"]


ceilings = [2 * ao(f"alone-{k}.json") / max(ao(f"together-{k}-a.json"), ao(f"together-{k}-b.json")) for k in range(1, 4)]
measured["ceiling"] = med(ceilings)
print("the node's ceiling for 2 ranks (2 x one process alone over the slower of two at once, no MPI): "
      + ", ".join(f"{c:.2f}x" for c in ceilings) + f"; median {med(ceilings):.2f}x")
(out / "measured.json").write_text(json.dumps(measured, indent=1))
