# The fastest spheres of a kept conveyor run's v_x dumps (dump.spread): where they were (x from the
# blade's front face, z above the plate, in µm) and how fast.
#   python3 fastest.py RUN_DIR/dump.spread BLADE_FRONT_X_M LIMIT_M_S
import sys
path = sys.argv[1]; front = float(sys.argv[2]); limit = float(sys.argv[3])
rows = []; step = None; n = 0; frames = 0
with open(path) as f:
    it = iter(f)
    for line in it:
        if line.startswith("ITEM: TIMESTEP"):
            step = int(next(it)); frames += 1
        elif line.startswith("ITEM: NUMBER OF ATOMS"):
            n = int(next(it))
        elif line.startswith("ITEM: ATOMS"):
            cols = line.split()[2:]
            for _ in range(n):
                v = dict(zip(cols, map(float, next(it).split())))
                rows.append((abs(v["vx"]), v["vx"], step, int(v["id"]), (v["x"] - front) * 1e6, v["z"] * 1e6))
rows.sort(reverse=True)
print(f"{frames} frames, {len(rows)} sphere-frames; |vx| > {limit} m/s: {sum(r[0] > limit for r in rows)}")
for r in rows[:15]:
    print(f"step {r[2]:8d} id {r[3]:6d} vx {r[1]:+.4f} m/s  x-front {r[4]:7.1f} um  z {r[5]:7.1f} um")
