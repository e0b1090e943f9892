"""A tessellated city as an STL triangle soup, for scenes that nobody tuned for: NX x NY buildings
(walls in 5 m cells, roofs in two triangles) on a ground of 2 m cells around them, with a TOML
scene that puts it under a sky (a panel at height 60 facing down, E = 1, rho = 0).

    python3 examples/tessellated-city.py 12 12 /tmp/city12   # writes city12.stl, city12.toml
    radiosity solve --scene /tmp/city12.toml --refine 0
    radiosity viewfactors --scene /tmp/city12.stl --refine 0 --tolerance 1e-6 --output F.npz

(the view factors among the buildings and the ground alone: each triangle's sky view factor is
1 minus its row sum).
"""
import struct, sys, random
nx, ny = int(sys.argv[1]), int(sys.argv[2])
out = sys.argv[3]
BLOCK, STREET, CELL, WCELL = 10.0, 6.0, 2.0, 5.0
rng = random.Random(7)
tris = []
def quad(a, b, c, d):  # counter-clockwise about the outward normal
    tris.append((a, b, c)); tris.append((a, c, d))
def lines(n):
    v = [0.0]
    for _ in range(n):
        v.append(v[-1] + STREET); v.append(v[-1] + BLOCK)
    v.append(v[-1] + STREET)
    return v
xs, ys = lines(nx), lines(ny)
W, H = xs[-1], ys[-1]
def in_building(x, y):
    for i in range(nx):
        if xs[2*i+1] <= x < xs[2*i+2]:
            for j in range(ny):
                if ys[2*j+1] <= y < ys[2*j+2]:
                    return True
    return False
# ground: 2 m cells
gx = [k * CELL for k in range(int(W / CELL) + 1)]
gy = [k * CELL for k in range(int(H / CELL) + 1)]
for a in range(len(gx) - 1):
    for b in range(len(gy) - 1):
        cx, cy = (gx[a] + gx[a+1]) / 2, (gy[b] + gy[b+1]) / 2
        if in_building(cx, cy):
            continue
        quad((gx[a], gy[b], 0), (gx[a+1], gy[b], 0), (gx[a+1], gy[b+1], 0), (gx[a], gy[b+1], 0))
for i in range(nx):
    for j in range(ny):
        x0, x1, y0, y1 = xs[2*i+1], xs[2*i+2], ys[2*j+1], ys[2*j+2]
        h = 10.0 + 5.0 * rng.randrange(7)
        rows = [h * k / round(h / WCELL) for k in range(round(h / WCELL) + 1)]
        cols = [k * WCELL for k in range(int(BLOCK / WCELL) + 1)]
        # walls: (origin, along) with outward normal = along x up
        for (o, u) in [((x0, y0), (1, 0)), ((x1, y0), (0, 1)), ((x1, y1), (-1, 0)), ((x0, y1), (0, -1))]:
            for c in range(len(cols) - 1):
                for r in range(len(rows) - 1):
                    p = lambda s, z: (o[0] + u[0] * s, o[1] + u[1] * s, z)
                    quad(p(cols[c], rows[r]), p(cols[c+1], rows[r]), p(cols[c+1], rows[r+1]), p(cols[c], rows[r+1]))
        quad((x0, y0, h), (x1, y0, h), (x1, y1, h), (x0, y1, h))
with open(out + ".stl", "wb") as f:
    f.write(b"\0" * 80 + struct.pack("<I", len(tris)))
    for t in tris:
        f.write(struct.pack("<3f", 0, 0, 0))
        for v in t:
            f.write(struct.pack("<3f", *v))
        f.write(b"\0\0")
name = out.split("/")[-1]
with open(out + ".toml", "w") as f:
    f.write(f'''name = "{name}"
[[faces]]
name = "sky"
vertices = [[0, 0, 60], [0, {H}, 60], [{W}, {H}, 60], [{W}, 0, 60]]
rho = 0.0
emission = 1.0
[[meshes]]
file = "{name}.stl"
rho = 0.3
''')
print(len(tris), "triangles")
