#!/usr/bin/env bash
# Builds the seed corpus of every fuzz target under OUT (default build/fuzz/seeds/<target>/)
# from the repository's own inputs (data/, examples/, the strings the tests feed the readers)
# and from the third-party files in ../shared/anchors, read in place (never copied into the
# repository). Scenes and projects become archive inputs (fuzz/fuzz_common.h) holding the
# files they link; large meshes are replaced by a small one of the same format, so that an
# input stays quick to run. Needs python3.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-build/fuzz/seeds}
anchors=${HOF_ANCHORS_DIR:-../shared/anchors}
rm -rf "$out"
mkdir -p "$out"
python3 - "$out" "$anchors" <<'PY'
import hashlib, os, re, struct, sys, glob

out, anchors = sys.argv[1], sys.argv[2]
TARGETS = ["msh", "obj", "stl", "off", "vtu", "hof", "scn", "sofa_legacy", "x3d", "trajectory", "udp", "session"]
for t in TARGETS:
    os.makedirs(os.path.join(out, t), exist_ok=True)

def seed(target, data):
    if isinstance(data, str):
        data = data.encode("utf-8", "surrogateescape")
    name = hashlib.sha1(data).hexdigest()
    with open(os.path.join(out, target, name), "wb") as f:
        f.write(data)

def read(path):
    with open(path, "rb") as f:
        return f.read()

# --- a small mesh (a cube of 5 tetrahedra and its 12 boundary triangles) in every format --
nodes = [(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1)]
nodes = [(0.01 * x, 0.01 * y, 0.01 * z) for x, y, z in nodes]
tets = [(0, 1, 3, 5), (0, 3, 2, 6), (0, 5, 6, 4), (3, 5, 6, 7), (0, 3, 6, 5)]
tris = [(0, 2, 3), (0, 3, 1), (4, 5, 7), (4, 7, 6), (0, 1, 5), (0, 5, 4),
        (2, 6, 7), (2, 7, 3), (0, 4, 6), (0, 6, 2), (1, 3, 7), (1, 7, 5)]
def msh22(binary=False):
    s = "$MeshFormat\n2.2 %d 8\n" % (1 if binary else 0)
    b = s.encode()
    if binary:
        b += struct.pack("<i", 1) + b"\n"
    b += b"$EndMeshFormat\n$Nodes\n%d\n" % len(nodes)
    for i, p in enumerate(nodes):
        b += struct.pack("<i3d", i + 1, *p) if binary else ("%d %g %g %g\n" % (i + 1, *p)).encode()
    b += b"$EndNodes\n$Elements\n%d\n" % (len(tets) + len(tris))
    if binary:
        b += struct.pack("<3i", 4, len(tets), 2)
        for i, t in enumerate(tets):
            b += struct.pack("<7i", i + 1, 1, 1, *[n + 1 for n in t])
        b += struct.pack("<3i", 2, len(tris), 2)
        for i, t in enumerate(tris):
            b += struct.pack("<6i", len(tets) + i + 1, 2, 2, *[n + 1 for n in t])
    else:
        for i, t in enumerate(tets):
            b += ("%d 4 2 1 1 %d %d %d %d\n" % (i + 1, *[n + 1 for n in t])).encode()
        for i, t in enumerate(tris):
            b += ("%d 2 2 2 2 %d %d %d\n" % (len(tets) + i + 1, *[n + 1 for n in t])).encode()
    return b + b"$EndElements\n"
def msh1():
    s = "$NOD\n%d\n" % len(nodes) + "".join("%d %g %g %g\n" % (i + 1, *p) for i, p in enumerate(nodes))
    s += "$ENDNOD\n$ELM\n%d\n" % (len(tets) + len(tris))
    s += "".join("%d 4 1 1 4 %d %d %d %d\n" % (i + 1, *[n + 1 for n in t]) for i, t in enumerate(tets))
    s += "".join("%d 2 2 2 3 %d %d %d\n" % (len(tets) + i + 1, *[n + 1 for n in t]) for i, t in enumerate(tris))
    return s + "$ENDELM\n"
def msh41():
    s = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n0 0 1 1\n1 0 0 0 0.01 0.01 0.01 0 0\n1 0 0 0 0.01 0.01 0.01 0 0\n$EndEntities\n"
    s += "$Nodes\n1 %d 1 %d\n3 1 0 %d\n" % (len(nodes), len(nodes), len(nodes))
    s += "".join("%d\n" % (i + 1) for i in range(len(nodes))) + "".join("%g %g %g\n" % p for p in nodes)
    s += "$EndNodes\n$Elements\n2 %d 1 %d\n" % (len(tets) + len(tris), len(tets) + len(tris))
    s += "2 1 2 %d\n" % len(tris) + "".join("%d %d %d %d\n" % (i + 1, *[n + 1 for n in t]) for i, t in enumerate(tris))
    s += "3 1 4 %d\n" % len(tets) + "".join("%d %d %d %d %d\n" % (len(tris) + i + 1, *[n + 1 for n in t]) for i, t in enumerate(tets))
    return s + "$EndElements\n"
obj = "# cube\n" + "".join("v %g %g %g\n" % p for p in nodes) + "vn 0 0 1\nvt 0 0\n" + \
      "".join("f %d/1/1 %d//1 %d\n" % tuple(n + 1 for n in t) for t in tris[:6]) + \
      "".join("f %d %d %d\n" % tuple(n - 8 for n in t) for t in tris[6:]) + "f 1 2 4 3\n"
def normal(t):
    a, b, c = (nodes[i] for i in t)
    u = [b[k] - a[k] for k in range(3)]; v = [c[k] - a[k] for k in range(3)]
    return (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
stl_ascii = "solid cube\n" + "".join(
    "facet normal %g %g %g\nouter loop\n%sendloop\nendfacet\n" % (*normal(t), "".join("vertex %g %g %g\n" % nodes[i] for i in t))
    for t in tris) + "endsolid cube\n"
stl_binary = b"solid but binary".ljust(80, b" ") + struct.pack("<I", len(tris)) + b"".join(
    struct.pack("<3f", *normal(t)) + b"".join(struct.pack("<3f", *nodes[i]) for i in t) + b"\0\0" for t in tris)
off = "OFF\n# cube\n%d %d 0\n" % (len(nodes), len(tris)) + "".join("%g %g %g\n" % p for p in nodes) + \
      "".join("3 %d %d %d\n" % t for t in tris)
vtu = ('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">\n'
       '<UnstructuredGrid>\n<Piece NumberOfPoints="%d" NumberOfCells="%d">\n<Points>\n'
       '<DataArray type="Float64" NumberOfComponents="3" format="ascii">\n%s</DataArray>\n</Points>\n<Cells>\n'
       '<DataArray type="Int32" Name="connectivity" format="ascii">\n%s</DataArray>\n'
       '<DataArray type="Int32" Name="offsets" format="ascii">\n%s</DataArray>\n'
       '<DataArray type="UInt8" Name="types" format="ascii">\n%s</DataArray>\n</Cells>\n'
       '<CellData>\n<DataArray type="Int32" Name="region" format="ascii">\n%s</DataArray>\n</CellData>\n'
       '<PointData>\n<DataArray type="Float64" Name="normals" NumberOfComponents="3" format="ascii">\n%s</DataArray>\n</PointData>\n'
       '</Piece>\n</UnstructuredGrid>\n</VTKFile>\n') % (
    len(nodes), len(tets) + len(tris), "".join("%g %g %g\n" % p for p in nodes),
    "".join(" ".join(map(str, t)) + "\n" for t in tets + tris),
    " ".join(str(4 * (i + 1)) for i in range(len(tets))) + " " + " ".join(str(4 * len(tets) + 3 * (i + 1)) for i in range(len(tris))) + "\n",
    "10 " * len(tets) + "5 " * len(tris) + "\n", "1 " * len(tets) + "2 " * len(tris) + "\n", "0 0 1\n" * len(nodes))
legacy_mesh = "".join("tetra %d %d %d %d\n" % t for t in tets) + "".join("triangle %d %d %d\n" % t for t in tris) + "line 0 1\n"
xs3 = "Xsp 3.0\nnumm %d\n" % len(nodes) + "".join("mass %d 0 %g %g %g 0 0 0 0.1 %d\n" % (i, *p, 1 if i < 2 else 0) for i, p in enumerate(nodes)) + \
      "lspg 0 1 100 1 0.01\n"
SMALL = {".msh": msh22(), ".obj": obj, ".stl": stl_ascii, ".off": off, ".vtu": vtu, ".mesh": legacy_mesh, ".xs3": xs3}

seed("msh", msh22()); seed("msh", msh22(True)); seed("msh", msh1()); seed("msh", msh41())
seed("obj", obj); seed("stl", stl_ascii); seed("stl", stl_binary); seed("off", off); seed("vtu", vtu)
seed("sofa_legacy", legacy_mesh); seed("sofa_legacy", xs3)

# --- the repository's and the anchors' mesh files (large ones are cut by -max_len) ----------
MESH_TARGET = {".msh": "msh", ".obj": "obj", ".stl": "stl", ".off": "off", ".vtu": "vtu", ".mesh": "sofa_legacy", ".xs3": "sofa_legacy"}
for root in ("data", "examples", "tests", anchors):
    for path in glob.glob(os.path.join(root, "**", "*"), recursive=True):
        ext = os.path.splitext(path)[1].lower()
        if ext in MESH_TARGET and os.path.isfile(path) and os.path.getsize(path) <= 200_000:
            seed(MESH_TARGET[ext], read(path))

# --- scenes and projects as archives with the files they link ---------------------------
REF = re.compile(rb'((?:filename|fileMesh|scene|mesh|url)\s*=\s*")([^"@]+\.(?:msh|obj|stl|off|vtu|mesh|xs3|scn|x3d|csv|sph))(")', re.I)
SAFE = re.compile(r"^[A-Za-z0-9._-]+(/[A-Za-z0-9._-]+){0,2}$")
def resolve(folder, ref):
    d = os.path.abspath(folder)
    while True:
        p = os.path.join(d, ref)
        if os.path.isfile(p):
            return p
        if d == "/":
            return None
        d = os.path.dirname(d)
def archive(path, main_name=None):
    files = {}
    def visit(p, name):
        text = read(p)
        def link(m):
            ref = m.group(2).decode("utf-8", "replace")
            target = resolve(os.path.dirname(p), ref)
            if target is None:
                return m.group(0)
            new = ref if SAFE.match(ref) and ".." not in ref else os.path.basename(ref)
            if new not in files:
                ext = os.path.splitext(target)[1].lower()
                if ext in (".scn", ".x3d", ".hof"):
                    files[new] = b""
                    files[new] = visit(target, new)
                else:
                    files[new] = read(target) if os.path.getsize(target) <= 40_000 or ext not in SMALL else \
                        (SMALL[ext] if isinstance(SMALL[ext], bytes) else SMALL[ext].encode())
            return m.group(1) + new.encode() + m.group(3)
        return REF.sub(link, text)
    main = visit(path, main_name)
    head = b"@@file " + main_name.encode() + b"\n" if main_name else b""
    return head + main + b"".join(b"\n@@file " + n.encode() + b"\n" + b for n, b in files.items())

scenes = sorted(glob.glob("examples/*.scn") + glob.glob(os.path.join(anchors, "sofa", "**", "*.scn"), recursive=True))
projects = sorted(glob.glob("examples/*.hof"))
x3ds = sorted(glob.glob(os.path.join(anchors, "h3d", "**", "*.x3d"), recursive=True))
for s in scenes:
    seed("scn", archive(s))
    seed("session", archive(s, "scene.scn"))
for p in projects:
    seed("hof", archive(p))
    seed("session", archive(p, "project.hof"))
for x in x3ds:
    if os.path.getsize(x) <= 100_000:
        seed("x3d", archive(x))
        seed("session", archive(x, "scene.x3d"))

# --- the inputs the tests feed the readers (string literals holding a whole file) -------
RAW = re.compile(r'R"([^(\s]{0,8})\((.*?)\)\1"', re.S)
def classify(text):
    t = text.lstrip()
    if "$MeshFormat" in t or "$NOD" in t: return ["msh"]
    if "<VTKFile" in t: return ["vtu"]
    if t.startswith("<hof") or "<hof " in t or "<hof>" in t: return ["hof", "session"]
    if "<X3D" in t or ("<Scene" in t and "<Shape" in t): return ["x3d", "session"]
    if "<Node" in t or "<Object" in t: return ["scn", "session"]
    if t.startswith("solid"): return ["stl"]
    if t.startswith("OFF"): return ["off"]
    if t.startswith("t,") or "\nt," in t: return ["trajectory"]
    if re.search(r"^(tetra|triangle) \d", t, re.M) or "numm" in t: return ["sofa_legacy"]
    if re.search(r"^v [-\d.]", t, re.M): return ["obj"]
    return []
def c_literals(src):
    # Runs of adjacent ordinary string literals ("a\n" "b\n"), unescaped.
    for m in re.finditer(r'(?:"(?:[^"\\\n]|\\.)*"\s*){1,}', src):
        parts = re.findall(r'"((?:[^"\\\n]|\\.)*)"', m.group(0))
        s = "".join(parts)
        if "\\n" in s and len(s) >= 16:
            try:
                yield s.encode("latin-1", "backslashreplace").decode("unicode_escape")
            except Exception:
                pass
for path in glob.glob("tests/**/*.cpp", recursive=True):
    src = read(path).decode("utf-8", "replace")
    texts = [m.group(2) for m in RAW.finditer(src)] + list(c_literals(src))
    for text in texts:
        for target in classify(text):
            seed(target, text if target != "session" else (
                "@@file scene.hof\n" if target == "session" and "<hof" in text else
                "@@file scene.x3d\n" if "<X3D" in text or "<Shape" in text else "") + text)

# --- trajectories and UDP datagrams ---------------------------------------------------
seed("trajectory", "# press\nt,x,y,z\n0,0,0.05,0\n0.5,0,0.01,0\n1,0,0.05,0\n")
seed("trajectory", "t,button,qw,qx,qy,qz,x,y,z\n0,0,1,0,0,0,0,0,0\n0.001,1,0.7,0.7,0,0,1e-3,0,0 # moved\n\n0.002,1,0,0,0,1,0,0,0\n")
def udp_state(vel):
    b = b"HOFS" + struct.pack("<HHII", 1, 1 if vel else 0, 7, 1) + struct.pack("<d", 0.25) + struct.pack("<3d", 0.01, 0.02, 0.03) + struct.pack("<4d", 1, 0, 0, 0)
    return b + (struct.pack("<3d", 0.1, 0, 0) if vel else b"")
seed("udp", udp_state(False)); seed("udp", udp_state(True))
seed("udp", b"HOFH" + struct.pack("<HHII", 1, 0, 3, 0) + struct.pack("<5d", 8, 3000, 20, 0.08, 1000) + b"falcon".ljust(32, b"\0"))
seed("udp", b"HOFF" + struct.pack("<HHII", 1, 0, 7, 9) + struct.pack("<6d", 0.5, 0, 0, 0, 0, 0))
seed("udp", b"HOFC" + struct.pack("<HHII", 2, 0, 3, 0))

for t in TARGETS:
    print("%-12s %4d seeds" % (t, len(os.listdir(os.path.join(out, t)))))
PY
