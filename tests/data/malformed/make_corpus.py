#!/usr/bin/env python3
"""Writes the malformed-input corpus beside this script: small broken files for every reader,
made from valid seeds by fixed mutations (truncation, bad numbers, wrong counts, trailing data,
control bytes, garbage). The manifest (MANIFEST.tsv: file, command, exit code, message fragment)
is kept by hand: each row was checked against the message the CLI gives. Rerun after changing a
seed; files that no longer appear in the manifest are reported."""
import gzip, os, struct, sys

HERE = os.path.dirname(os.path.abspath(__file__))
FILES = os.path.join(HERE, "files")

def quad_off():
    return b"OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n"

def quad_obj():
    return b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"

def quad_stl_ascii():
    return (b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nendloop\nendfacet\n"
            b"endsolid t\n")

def quad_stl_binary(count=1, tris=1):
    body = b"".join(struct.pack("<12fH", 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 1, 0, 0) for _ in range(tris))
    return b"\0" * 80 + struct.pack("<I", count) + body

def mesh_ply_ascii():
    return (b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
            b"element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n")

def points_ply_binary(n=12, declared=None):
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
            "property float z\nend_header\n" % (n if declared is None else declared)).encode()
    return head + b"".join(struct.pack("<3f", i, i * i % 7, i % 3) for i in range(n))

def xyz():
    return b"".join(b"%d %d %d\n" % (i, i * i % 7, i % 3) for i in range(12))

def slim2t(n=2, declared=None):
    out = struct.pack("<3i", 2, n if declared is None else declared, 0)
    for i in range(n):
        out += struct.pack("<3f", i, 0, 0) + struct.pack("<10f", 1, 1, 1, 0, 0, 0, -2 * i, 0, 0, i * i - 1)
        out += struct.pack("<2f", 1.0, -1.0)
    return out

def nhdr(data_file="v.raw", sizes=b"4 4 4", extra=b""):
    return (b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: " + sizes + b"\nspacings: 1 1 1\nencoding: raw\n" + extra +
            b"data file: " + data_file.encode() + b"\n")

def nrrd_attached(payload=bytes(range(64))):
    return b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 4 4\nencoding: raw\n\n" + payload

def inr(xdim=4, body=64, type_line=b"TYPE=unsigned fixed\nPIXSIZE=8 bits\n"):
    head = b"#INRIMAGE-4#{\nXDIM=%d\nYDIM=4\nZDIM=4\nVDIM=1\n" % xdim + type_line + b"CPU=decm\n"
    head += b"\n" * (252 - len(head)) + b"##}\n"
    return head + bytes(i % 256 for i in range(body))

def medit_mesh():
    return (b"MeshVersionFormatted 1\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\n"
            b"Tetrahedra\n1\n1 2 3 4 0\nEnd\n")

def cin():
    return b"0 0 0 1\n1.5 0 0 1\n0 1.5 0 1\n0 0 1.5 1\n0.7 0.7 0.7 0.5\n"

def pdb():
    lines = []
    for i, (x, y, z, e) in enumerate([(0, 0, 0, "C"), (1.5, 0, 0, "O"), (0, 1.5, 0, "N"), (0, 0, 1.5, "C")]):
        lines.append("ATOM  %5d  %-3s ALA A   1    %8.3f%8.3f%8.3f  1.00  0.00          %2s" % (i + 1, e, x, y, z, e))
    return ("\n".join(lines) + "\nEND\n").encode()

def implicit_qxm(expression=b"x^2 + y^2 + z^2 - r^2", params=(1.0,), bounds=(-2, -2, -2, 2, 2, 2), count=None,
                 props=b"property double min_x\nproperty double min_y\nproperty double min_z\n"
                       b"property double max_x\nproperty double max_y\nproperty double max_z\n"):
    """An ASCII .qxm with one implicit surface (element rows with two lists)."""
    head = (b"ply\nformat ascii 1.0\ncomment quadrix-format 2\nelement implicit 1\n"
            b"property list uint uchar expression\nproperty list uchar double parameters\n" + props + b"end_header\n")
    n = len(expression) if count is None else count
    row = [b"%d" % n] + [b"%d" % c for c in expression] + [b"%d" % len(params)]
    row += [repr(float(v)).encode() for v in params] + [b"%g" % v for v in bounds]
    return head + b" ".join(row) + b"\n"

def mutate_text(seed):
    """Mutations of a whitespace-token text file: (suffix, bytes)."""
    # Truncations end inside a token (a cut at a line end can leave a valid file).
    def cut(at):
        while at > 1 and seed[at - 1:at] in (b"\n", b" "):
            at -= 1
        return seed[:at]
    out = [("empty", b""), ("trunc50", cut(len(seed) // 2)), ("trunc90", cut(len(seed) * 9 // 10)),
           ("ctrl", seed.replace(b"\n", b"\n\x01\x02\x1b[31m", 1)), ("nul", seed[:10] + b"\0\0\0" + seed[10:]),
           ("garbage", bytes((i * 37 + 11) % 256 for i in range(200))),
           ("longtoken", seed.replace(b"1", b"9" * 3000, 1))]
    toks = seed.split(b" ")
    for k, bad in (("nan", b"nan"), ("inf", b"1e999"), ("word", b"abc")):
        i = len(toks) // 2
        out.append((k, b" ".join(toks[:i] + [bad] + toks[i + 1:])))
    return out

def main():
    os.makedirs(FILES, exist_ok=True)
    files = {}
    def put(name, data):
        files[name] = data
    # Seeds with their mutations.
    for ext, seed in ((".off", quad_off()), (".obj", quad_obj()), (".xyz", xyz()), (".cin", cin()),
                      (".mesh", medit_mesh()), ("-ascii.ply", mesh_ply_ascii()),
                      ("-ascii.stl", quad_stl_ascii())):
        for suffix, data in mutate_text(seed):
            put(suffix + ext, data)
    # .qxm models (binary seeds written by `quadrix synth`, beside this script).
    for seed_name, element in (("seed-tet.qxm", b"tet"), ("seed-slim.qxm", b"slim")):
        seed = open(os.path.join(HERE, seed_name), "rb").read()
        head, body = seed.split(b"end_header\n", 1)
        count_at = head.index(b"element " + element + b" ") + len(b"element " + element + b" ")
        count_end = head.index(b"\n", count_at)
        n = int(head[count_at:count_end])
        def with_count(c):
            return head[:count_at] + str(c).encode() + head[count_end:] + b"end_header\n" + body
        kind = element.decode()
        put("count-small-%s.qxm" % kind, with_count(n - 1))
        put("count-zero-%s.qxm" % kind, with_count(0))
        put("count-big-%s.qxm" % kind, with_count(n + 1))
        put("count-huge-%s.qxm" % kind, with_count(1 << 40))
        put("truncated-%s.qxm" % kind, seed[:-7])
        put("ascii-header-%s.qxm" % kind, seed.replace(b"binary_little_endian", b"ascii"))
        put("no-quadrix-comment-%s.qxm" % kind, seed.replace(b"comment quadrix-format", b"comment other-format"))
        put("version-%s.qxm" % kind, seed.replace(b"quadrix-format 2", b"quadrix-format 99"))
        put("nan-%s.qxm" % kind, head + b"end_header\n" + struct.pack("<d", float("nan")) + body[8:])
        put("inf-%s.qxm" % kind, head + b"end_header\n" + struct.pack("<d", float("inf")) + body[8:])
        put("no-end-header-%s.qxm" % kind, head + b"\n")
    # Implicit surfaces in .qxm.
    put("implicit-syntax.qxm", implicit_qxm(b"x^2 + * y", ()))
    put("implicit-function.qxm", implicit_qxm(b"x^2 + frob(y)", ()))
    put("implicit-param-count.qxm", implicit_qxm(params=()))
    put("implicit-param-nan.qxm", implicit_qxm(params=(float("nan"),)))
    put("implicit-bounds-empty.qxm", implicit_qxm(bounds=(1, -2, -2, -1, 2, 2)))
    put("implicit-bounds-inf.qxm", implicit_qxm(bounds=(-2, -2, -2, 2, float("inf"), 2)))
    put("implicit-ctrl.qxm", implicit_qxm(b"x^2 + \x1b[2J y^2 - 1", ()))
    put("implicit-empty.qxm", implicit_qxm(b"", ()))
    put("implicit-list-count.qxm", implicit_qxm(count=1000))
    put("implicit-no-bounds.qxm", implicit_qxm(bounds=(-2, -2, -2, 2, 2), props=b"property double min_x\n"
        b"property double min_y\nproperty double min_z\nproperty double max_x\nproperty double max_y\n"))
    # The compact encoding (seed written by `quadrix synth hyperboloid1 --resolution 2`): the
    # origin and encoding lines, and float32 rows.
    seed = open(os.path.join(HERE, "seed-compact.qxm"), "rb").read()
    head, body = seed.split(b"end_header\n", 1)
    origin_at = head.index(b"comment quadrix-origin ")
    origin_end = head.index(b"\n", origin_at) + 1
    def with_origin(line):
        return head[:origin_at] + line + head[origin_end:] + b"end_header\n" + body
    put("compact-no-origin.qxm", with_origin(b""))
    put("compact-origin-nan.qxm", with_origin(b"comment quadrix-origin nan 0 0\n"))
    put("compact-origin-short.qxm", with_origin(b"comment quadrix-origin 1 2\n"))
    put("compact-origin-word.qxm", with_origin(b"comment quadrix-origin 1 2 three\n"))
    put("compact-origin-twice.qxm", with_origin(head[origin_at:origin_end] * 2))
    put("compact-encoding-bad.qxm", seed.replace(b"quadrix-encoding compact", b"quadrix-encoding zipped"))
    put("compact-revision-2.qxm", seed.replace(b"quadrix-format 3", b"quadrix-format 2"))
    put("compact-truncated.qxm", seed[:-7])
    put("compact-nan.qxm", head + b"end_header\n" + struct.pack("<f", float("nan")) + body[4:])
    put("compact-count-big.qxm", head.replace(b"element tet ", b"element tet 1") + b"end_header\n" + body)
    put("empty.qxm", b"")
    put("text.qxm", b"hello\n")
    # Counts and trailing data.
    put("count-huge.off", b"OFF\n1073741824 1 0\n0 0 0\n")
    put("count-negative.off", b"OFF\n-4 1 0\n0 0 0\n")
    put("vertex-short.off", quad_off().replace(b"1 1 0\n", b"1 1\n"))
    put("header-only.off", b"OFF\n")
    put("face-two.obj", quad_obj().replace(b"f 1 2 3 4", b"f 1 2"))
    put("no-faces.obj", b"v 0 0 0\nv 1 0 0\n")
    put("vertex-short-ascii.stl", quad_stl_ascii().replace(b"vertex 1 1 0", b"vertex 1 1"))
    put("no-endsolid-ascii.stl", quad_stl_ascii().replace(b"endsolid t\n", b""))
    put("nan-third-line.xyz", xyz().replace(b"2 4 2", b"2 nan 2"))
    put("columns-mixed.xyz", xyz().replace(b"3 2 0\n", b"3 2 0 0 0 1\n"))
    put("trailing.off", quad_off() + b"7 7 7\n")
    put("face-index-out.off", quad_off().replace(b"4 0 1 2 3", b"4 0 1 2 9"))
    put("face-index-negative.off", quad_off().replace(b"4 0 1 2 3", b"4 0 1 2 -1"))
    put("face-too-small.off", quad_off().replace(b"4 0 1 2 3", b"2 0 1"))
    put("index-min.obj", quad_obj().replace(b"f 1 2 3 4", b"f 1 2 3 -9223372036854775808"))
    put("index-huge.obj", quad_obj().replace(b"f 1 2 3 4", b"f 1 2 3 99999999999999999999"))
    put("index-zero.obj", quad_obj().replace(b"f 1 2 3 4", b"f 0 1 2 3"))
    put("index-word.obj", quad_obj().replace(b"f 1 2 3 4", b"f 1 2 3 x"))
    put("vertex-short.obj", quad_obj().replace(b"v 1 1 0", b"v 1 1"))
    put("count-huge.stl", quad_stl_binary(count=100000000))
    put("count-small.stl", quad_stl_binary(count=1, tris=2))
    put("truncated.stl", quad_stl_binary()[:100])
    put("count-huge-ascii.ply", mesh_ply_ascii().replace(b"element vertex 4", b"element vertex 4000000000"))
    put("trailing-ascii.ply", mesh_ply_ascii() + b"5 5 5\n")
    put("no-end-header.ply", mesh_ply_ascii().replace(b"end_header\n", b""))
    put("bad-format.ply", mesh_ply_ascii().replace(b"format ascii 1.0", b"format zip 9.0"))
    put("bad-property-type.ply", mesh_ply_ascii().replace(b"property float y", b"property quad y"))
    put("points-count-huge.ply", points_ply_binary(declared=1 << 40))
    put("points-count-small.ply", points_ply_binary(declared=11))
    put("points-truncated.ply", points_ply_binary()[:-5])
    put("points-nan.ply", points_ply_binary().replace(struct.pack("<3f", 5, 4, 2), struct.pack("<3f", float("nan"), 4, 2)))
    put("binary-over-ascii.ply", mesh_ply_ascii().replace(b"format ascii 1.0", b"format binary_little_endian 1.0"))
    # SLIM .slim2t (binary) and .qxm models.
    put("count-small.slim2t", slim2t(declared=1))
    put("count-huge.slim2t", slim2t(declared=1 << 30))
    put("count-negative.slim2t", slim2t(declared=-2))
    put("truncated.slim2t", slim2t()[:-3])
    put("version.slim2t", struct.pack("<3i", 7, 0, 0))
    put("radius-nan.slim2t", slim2t().replace(struct.pack("<2f", 1.0, -1.0), struct.pack("<2f", float("nan"), -1.0), 1))
    put("parent-bad.slim2t", slim2t().replace(struct.pack("<2f", 1.0, -1.0), struct.pack("<2f", 1.0, 5.0), 1))
    # Volumes.
    raw = bytes(range(64))
    put("v.raw", raw)
    put("data-dev-zero.nhdr", nhdr("/dev/zero"))
    put("data-missing.nhdr", nhdr("nothere.raw"))
    put("data-folder.nhdr", nhdr("."))
    put("sizes-word.nhdr", nhdr(sizes=b"4 4 x"))
    put("sizes-two.nhdr", nhdr(sizes=b"4 4"))
    put("sizes-zero.nhdr", nhdr(sizes=b"4 0 4"))
    put("sizes-huge.nhdr", nhdr(sizes=b"100000 100000 100000"))
    put("sizes-big.nhdr", nhdr(sizes=b"8 8 8"))
    put("spacing-zero.nhdr", nhdr().replace(b"spacings: 1 1 1", b"spacings: 1 0 1"))
    put("type-bad.nhdr", nhdr().replace(b"type: uint8", b"type: complex"))
    put("encoding-bad.nhdr", nhdr().replace(b"encoding: raw", b"encoding: jpeg"))
    put("magic-bad.nhdr", nhdr().replace(b"NRRD0004", b"NRRX0004"))
    put("no-type.nhdr", nhdr().replace(b"type: uint8\n", b""))
    put("ctrl.nhdr", nhdr().replace(b"type: uint8", b"type: \x01\x02\x1b[2J"))
    put("dimension-4.nhdr", nhdr().replace(b"dimension: 3", b"dimension: 4"))
    put("gzip-bad.nhdr", nhdr().replace(b"encoding: raw", b"encoding: gzip"))
    put("short.nrrd", nrrd_attached(bytes(range(40))))
    put("long.nrrd", nrrd_attached(bytes(range(80))))
    put("no-blank-line.nrrd", b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 4 4\nencoding: raw\n")
    put("short.inr", inr(body=40))
    put("long.inr", inr(body=80))
    put("xdim-zero.inr", inr(xdim=0))
    put("xdim-huge.inr", inr(xdim=1 << 30))
    put("type-bad.inr", inr(type_line=b"TYPE=complex\nPIXSIZE=8 bits\n"))
    put("pixsize-bad.inr", inr(type_line=b"TYPE=unsigned fixed\nPIXSIZE=13 bits\n"))
    put("header-short.inr", inr()[:100])
    put("bomb.inr.gz", gzip.compress(inr(body=64) + bytes(4 << 20), 9, mtime=0))
    put("corrupt.inr.gz", gzip.compress(inr(), mtime=0)[:40] + b"\xff" * 20)
    # Tetrahedral meshes (convert volume --tets FILE --values FILE).
    put("values4.txt", b"0\n1\n0.5\n0.2\n")
    put("tet-index-out.mesh", medit_mesh().replace(b"1 2 3 4 0", b"1 2 3 9 0"))
    put("tet-count-huge.mesh", medit_mesh().replace(b"Tetrahedra\n1\n", b"Tetrahedra\n1000000000\n"))
    put("vertices-count-huge.mesh", medit_mesh().replace(b"Vertices\n4\n", b"Vertices\n1000000000\n"))
    put("flat-tet.mesh", medit_mesh().replace(b"0 0 1 0\n", b"1 1 0 0\n"))
    put("no-dimension.mesh", medit_mesh().replace(b"Dimension 3\n", b""))
    put("dimension-2.mesh", medit_mesh().replace(b"Dimension 3", b"Dimension 2"))
    # Vertex values (convert volume --tets tet4.mesh --values FILE) and ellipsoid rows (convert glyphs
    # --ellipsoids FILE).
    put("tet4.mesh", medit_mesh())
    put("values-word.txt", b"0\n1\nx\n0.2\n")
    put("values-few.txt", b"0\n1\n0.5\n")
    put("values-many.txt", b"0\n1\n0.5\n0.2\n7\n")
    put("values-nan.txt", b"0\n1\nnan\n0.2\n")
    put("values-empty.txt", b"# nothing\n")
    ell = b"cx,cy,cz,a1x,a1y,a1z,a2x,a2y,a2z,a3x,a3y,a3z,r,g,b\n0,0,0,1,0,0,0,2,0,0,0,3,255,0,0\n"
    put("ellipsoid-singular.csv", ell.replace(b"0,0,3,", b"0,0,0,"))
    put("ellipsoid-columns.csv", ell.replace(b"0,0,3,255,0,0", b"0,0"))
    put("ellipsoid-16.csv", ell.replace(b"255,0,0", b"255,0,0,1"))
    put("ellipsoid-colour.csv", ell.replace(b"255,0,0", b"300,0,0"))
    put("ellipsoid-word.csv", ell.replace(b"\n0,0,0,1,", b"\n0,0,0,one,"))
    put("ellipsoid-nan.csv", ell.replace(b"\n0,0,0,1,", b"\n0,nan,0,1,"))
    put("ellipsoid-none.csv", ell.split(b"\n")[0] + b"\n# no rows\n")
    put("ellipsoid-far.csv", ell.replace(b"\n0,0,0,1,", b"\n1e300,0,0,1,"))
    put("ellipsoid-axis-huge.csv", ell.replace(b",0,2,0,", b",0,2e300,0,"))
    # Balls.
    put("radius-negative.cin", cin().replace(b"0.7 0.7 0.7 0.5", b"0.7 0.7 0.7 -0.5"))
    put("columns-3.cin", cin().replace(b"0.7 0.7 0.7 0.5", b"0.7 0.7 0.7"))
    put("coord-huge.cin", cin().replace(b"0.7 0.7 0.7 0.5", b"1e308 0.7 0.7 0.5"))
    put("no-atoms.pdb", b"HEADER    nothing\nEND\n")
    put("coord-word.pdb", pdb().replace(b"   1.500", b"   x.yyy", 1))
    put("radius-negative.xyzr", b"0 0 0 1\n1.5 0 0 -1\n0 1.5 0 1\n0 0 1.5 1\n")
    put("columns.xyzr", b"0 0 0 1\n1.5 0 0\n")
    # Points.
    put("too-few.xyz", b"0 0 0\n1 0 0\n")
    put("coincide.xyz", b"1 2 3\n" * 50)
    put("columns-5.xyz", b"0 0 0 1 1\n1 0 0 1 1\n")
    put("coord-huge.xyz", xyz() + b"1e308 0 0\n")
    # Trailing data, TetGen pairs, bounded decompression, extreme but finite values (exit 3).
    node = b"4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"
    ele = b"1 4 0\n1 1 2 3 4\n"
    put("trailing.mesh", medit_mesh() + b"Vertices\n")
    put("coord-huge.mesh", medit_mesh().replace(b"1 0 0 0\n", b"1e300 0 0 0\n"))
    put("trailing.node", node + b"5 1 1 1\n")
    put("trailing.ele", ele)
    put("ele-trailing.node", node)
    put("ele-trailing.ele", ele + b"2 1 2 3 4\n")
    put("ele-short.node", node)
    put("ele-short.ele", b"2 4 0\n1 1 2 3 4\n")
    put("ele-index.node", node)
    put("ele-index.ele", ele.replace(b"1 1 2 3 4", b"1 1 2 3 7"))
    put("node-word.node", node.replace(b"3 0 1 0", b"3 0 x 0"))
    put("node-word.ele", ele)
    put("spacing-huge.nhdr", nhdr().replace(b"spacings: 1 1 1", b"spacings: 1 1e308 1"))
    put("origin-huge.nhdr", nhdr(extra=b"space origin: (1e300,0,0)\n"))
    put("byte-skip-negative.nhdr", nhdr(extra=b"byte skip: -2\n"))
    put("byte-skip-word.nhdr", nhdr(extra=b"byte skip: 1x\n"))
    put("v.raw.gz", gzip.compress(raw + bytes(4 << 20), 9, mtime=0))
    put("gzip-bomb.nhdr", nhdr("v.raw.gz").replace(b"encoding: raw", b"encoding: gzip"))
    put("gzip-bomb.nrrd", nrrd_attached(gzip.compress(bytes(4 << 20), 9, mtime=0)).replace(b"encoding: raw", b"encoding: gzip"))
    put("gzip-trailing.nrrd", nrrd_attached(gzip.compress(raw, 9, mtime=0) + b"junk").replace(b"encoding: raw", b"encoding: gzip"))
    put("spacing-huge.inr", inr(type_line=b"TYPE=unsigned fixed\nPIXSIZE=8 bits\nVY=1e308\n"))
    put("weight-huge.cin", cin().replace(b"0.7 0.7 0.7 0.5", b"0.7 0.7 0.7 1e300"))
    put("radius-huge.xyzr", b"0 0 0 1\n1.5 0 0 1e300\n0 1.5 0 1\n0 0 1.5 1\n")
    put("coord-1e300.off", quad_off().replace(b"1 1 0\n", b"1e300 1 0\n"))
    put("coord-1e300.obj", quad_obj().replace(b"v 1 1 0", b"v 1e300 1 0"))
    put("coord-1e300-ascii.stl", quad_stl_ascii().replace(b"vertex 1 1 0", b"vertex 1e300 1 0"))
    put("coord-1e300.xyz", xyz() + b"1e300 0 0\n")
    put("count-huge.pts", b"\n44444444444444444444\n\r\n3\n3")  # found by fuzzing: a count past long long
    put("implicit-deep.qxm", implicit_qxm(expression=b"(" * 3000 + b"x"))  # found by fuzzing: stack overflow
    put("record-non-ascii.pdb", b"\xf7")  # found by fuzzing: gemmi's record-name shift of a byte >= 0x80
    # found by fuzzing: a NUL cut gemmi's copy of a line, the next LINK record was read past its end
    put("nul-byte.pdb", pdb().replace(b"   1.500", b"   1.\x0000", 1))
    # a gzipped molecule promises no size: it may inflate to 32 times its compressed size, at least 1 MiB
    remarks = b"".join(b"REMARK 999 %-69s\n" % (b"padding %d" % (i % 10)) for i in range(26000))  # 2 MiB
    put("bomb.pdb.gz", gzip.compress(remarks + pdb(), 9, mtime=0))
    put("bomb.cif.gz", gzip.compress(b"data_bomb\n" + remarks.replace(b"REMARK 999", b"#         ") + b"#\n", 9, mtime=0))
    far = slim2t()
    far = far[:12 + 60] + struct.pack("<f", 1e30) + far[12 + 64:]  # ball 1's centre x (60 bytes a ball)
    put("centre-huge.slim2t", far)
    for seed_name, kind in (("seed-tet.qxm", "tet"), ("seed-slim.qxm", "slim")):
        seed = open(os.path.join(HERE, seed_name), "rb").read()
        head, body = seed.split(b"end_header\n", 1)
        put("scaled-1e300-%s.qxm" % kind, head + b"end_header\n" + struct.pack("<d", 1e300) + body[8:])
    for valid in ("trunc50.cin", "trunc90.xyz"):  # these cuts fall between records: valid files
        del files[valid]
    for name, data in files.items():
        with open(os.path.join(FILES, name), "wb") as f:
            f.write(data)
    os.makedirs(os.path.join(FILES, "folder.qxm"), exist_ok=True)
    os.makedirs(os.path.join(FILES, "folder.xyz"), exist_ok=True)
    os.makedirs(os.path.join(FILES, "folder.nhdr"), exist_ok=True)
    with open(os.path.join(FILES, "folder.qxm", "keep"), "w"):
        pass
    with open(os.path.join(FILES, "folder.xyz", "keep"), "w"):
        pass
    with open(os.path.join(FILES, "folder.nhdr", "keep"), "w"):
        pass
    print(len(files), "files written to", FILES)

if __name__ == "__main__":
    main()
