# Per-shading-point cost (µs) from a criterion log of `cargo bench -p samplers --bench strategies`:
# the middle estimate of each "time: [lo mid hi]" line divided by the shading points per iteration.
import re, sys
log = open(sys.argv[1]).read()
points = dict(re.findall(r"^(\S+): (\d+) shading points per iteration", log, re.M))
unit = {"ns": 1e-3, "µs": 1.0, "ms": 1e3, "s": 1e6}
cost = {}
for g, n, mid, u in re.findall(r"^([a-z-]+)/(\S+)\s+time:\s+\[\S+ \S+ (\S+) (\S+) \S+ \S+\]", log, re.M):
    cost[(g, n)] = float(mid) * unit[u] / int(points[g])
groups = [g for g in ["glossy-spheres", "emissive-mesh", "bisml-cornell"] if any(k[0] == g for k in cost)]
names = []
for (g, n) in cost:
    if n not in names:
        names.append(n)
print("| strategy | " + " | ".join(groups) + " |")
print("|---|" + "---:|" * len(groups))
for n in names:
    print("| `%s` | " % n + " | ".join("%.2f" % cost[(g, n)] if (g, n) in cost else "–" for g in groups) + " |")
