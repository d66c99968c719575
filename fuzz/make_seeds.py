#!/usr/bin/env python3
"""Seed inputs that are not files of the repository: a tiny Quake 3 map (the tests' tinyWriter
map of tests/test_bsp.cpp, byte for byte), .pk3 archives holding it, and GLB files made from
glTF files. Usage: make_seeds.py OUT_DIR [GLTF ...] -- writes OUT_DIR/bsp/tiny.bsp,
OUT_DIR/pk3/tiny-{deflated,stored}.pk3 and OUT_DIR/glb/NAME.glb for every GLTF (its buffers,
embedded as data: URIs or files next to it, become the GLB's binary chunk), and OUT_DIR/image/:
small PNGs (gray, gray + alpha, RGB, RGBA, palette; 8 and 16 bits) and uncompressed scanline EXRs
(float, half and uint channels, a data window off the origin) for readImage."""
import base64, json, os, struct, sys, zipfile, zlib

L_ENT, L_SHD, L_PLN, L_NOD, L_LEF, L_LFC, L_LBR, L_MOD, L_BRU, L_BSD, L_VTX, L_MSV, L_EFF, L_FAC, L_LMP, L_LVL, L_VIS = range(17)


class Bsp:
    def __init__(self):
        self.lump = [bytearray() for _ in range(17)]

    def i32(self, l, *vs):
        for v in vs:
            self.lump[l] += struct.pack('<i', v)

    def f32(self, l, *vs):
        for v in vs:
            self.lump[l] += struct.pack('<f', v)

    def shader(self, name, flags, contents):
        self.lump[L_SHD] += name.encode().ljust(64, b'\0')
        self.i32(L_SHD, flags, contents)

    def leaf(self, cluster, lo, hi, first, n):
        self.i32(L_LEF, cluster, 0, *[int(x) for x in lo], *[int(x) for x in hi], first, n, 0, 0)

    def vertex(self, p, n=(0, 0, 1)):
        idx = len(self.lump[L_VTX]) // 44
        self.f32(L_VTX, *p, 0, 0, 0, 0, *n)
        self.i32(L_VTX, -1)
        return idx

    def meshverts(self, l):
        first = len(self.lump[L_MSV]) // 4
        self.i32(L_MSV, *l)
        return first

    def face(self, shader, type_, vertex, nv, mv, nmv, w=0, h=0):
        self.i32(L_FAC, shader, -1, type_, vertex, nv, mv, nmv, 0, 0, 0, 0, 0)
        self.f32(L_FAC, *([0.0] * 12))
        self.i32(L_FAC, w, h)

    def file(self):
        out = bytearray(8 + 8 * 17)
        out[0:4] = b'IBSP'
        out[4] = 46
        for l in range(17):
            while len(out) % 4:
                out.append(0)
            struct.pack_into('<II', out, 8 + 8 * l, len(out), len(self.lump[l]))
            out += self.lump[l]
        return bytes(out)


def tiny_bsp():
    w = Bsp()
    w.lump[L_ENT] += (b'{\n"classname" "worldspawn"\n}\n'
                      b'{\n"classname" "info_player_deathmatch"\n"origin" "50 0 24"\n"angle" "90"\n}\n'
                      b'{\n"classname" "info_player_start"\n"origin" "-50 0 24"\n"angles" "10 180 0"\n}\n'
                      b'// a comment\n'
                      b'{\n"classname" "info_player_intermission"\n"origin" "0 0 200"\n"target" "t1"\n}\n'
                      b'{\n"classname" "target_position"\n"targetname" "t1"\n"origin" "50 0 0"\n}\n\0')
    w.shader('textures/base/floor', 0, 1)
    w.shader('textures/skies/sky', 0x4, 0)
    w.shader('textures/liquids/water', 0, 0x20 | 0x20000000)
    w.f32(L_PLN, 1, 0, 0, 0)
    w.f32(L_PLN, 1, 0, 0, 100)
    w.i32(L_NOD, 0, 1, -2, 0, 0, 0, 0, 0, 0)
    w.i32(L_NOD, 1, -3, -1, 0, 0, 0, 0, 0, 0)
    w.i32(L_LFC, 0, 2, 4, 5, 6, 1, 3, 6)
    w.leaf(0, (0, -64, -16), (100, 64, 128), 0, 5)
    w.leaf(1, (-100, -64, -16), (0, 64, 128), 5, 3)
    w.leaf(-1, (100, -64, -16), (200, 64, 128), 8, 0)
    v = w.vertex((10, 40, 0)); w.vertex((90, 40, 0)); w.vertex((90, -40, 0)); w.vertex((10, -40, 0))
    w.face(0, 1, v, 4, w.meshverts([0, 1, 2, 0, 2, 3]), 6)
    v = w.vertex((-90, 40, 0)); w.vertex((-10, 40, 0)); w.vertex((-10, -40, 0))
    w.face(0, 3, v, 3, w.meshverts([0, 1, 2]), 3)
    v = -1
    for i in range(3):
        for j in range(3):
            k = w.vertex((20.0 + 30 * j, -30.0 + 30 * i, 8))
            if v < 0:
                v = k
    w.face(0, 2, v, 9, 0, 0, 3, 3)
    v = w.vertex((-90, 40, 120)); w.vertex((-10, 40, 120)); w.vertex((-10, -40, 120))
    w.face(1, 1, v, 3, w.meshverts([0, 1, 2]), 3)
    v = w.vertex((50, 0, 64))
    w.face(0, 4, v, 1, 0, 0)
    v = w.vertex((10, 40, -8)); w.vertex((90, 40, -8)); w.vertex((90, -40, -8))
    w.face(2, 1, v, 3, w.meshverts([0, 1, 2]), 3)
    v = w.vertex((-20, 50, 4)); w.vertex((20, 50, 4)); w.vertex((20, 30, 4))
    w.face(0, 1, v, 3, w.meshverts([0, 1, 2]), 3)
    v = w.vertex((40, 60, 2)); w.vertex((60, 60, 2)); w.vertex((60, 50, 2))
    w.face(0, 1, v, 3, w.meshverts([0, 1, 2]), 3)
    v = w.vertex((20, 10, 30)); w.vertex((30, 10, 30)); w.vertex((30, -10, 30)); w.vertex((20, -10, 30))
    w.face(0, 1, v, 4, w.meshverts([0, 1, 2, 0, 2, 3]), 6)
    w.f32(L_MOD, -100, -64, -16, 200, 64, 128); w.i32(L_MOD, 0, 8, 0, 0)
    w.f32(L_MOD, 20, -10, 30, 30, 10, 30); w.i32(L_MOD, 8, 1, 0, 0)
    w.i32(L_VIS, 2, 1)
    w.lump[L_VIS] += bytes([1, 2])
    return w.file()


def glb_from_gltf(path):
    """One GLB: the glTF's buffers concatenated (4-byte aligned) into the BIN chunk."""
    doc = json.load(open(path))
    blob = bytearray()
    offsets = []
    for b in doc.get('buffers', []):
        uri = b.pop('uri', '')
        if uri.startswith('data:'):
            data = base64.b64decode(uri.split(',', 1)[1])
        else:
            data = open(os.path.join(os.path.dirname(path), uri), 'rb').read()
        while len(blob) % 4:
            blob.append(0)
        offsets.append(len(blob))
        blob += data[:b['byteLength']]
    for v in doc.get('bufferViews', []):
        v['byteOffset'] = v.get('byteOffset', 0) + offsets[v['buffer']]
        v['buffer'] = 0
    doc['buffers'] = [{'byteLength': len(blob)}] if blob else []
    js = json.dumps(doc, separators=(',', ':')).encode()
    js += b' ' * (-len(js) % 4)
    blob += b'\0' * (-len(blob) % 4)
    chunks = struct.pack('<II', len(js), 0x4E4F534A) + js
    if blob:
        chunks += struct.pack('<II', len(blob), 0x004E4942) + blob
    return struct.pack('<III', 0x46546C67, 2, 12 + len(chunks)) + chunks


def png(w, h, color_type, depth, rows, palette=None):
    """A PNG: IHDR, optional PLTE, one zlib IDAT of the rows (filter byte 0 each), IEND."""
    def chunk(kind, data):
        return struct.pack('>I', len(data)) + kind + data + struct.pack('>I', zlib.crc32(kind + data))
    raw = b''.join(b'\0' + r for r in rows)
    out = b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, depth, color_type, 0, 0, 0))
    if palette:
        out += chunk(b'PLTE', palette)
    return out + chunk(b'IDAT', zlib.compress(raw)) + chunk(b'IEND', b'')


def exr(w, h, channels, x0=0, y0=0):
    """An OpenEXR file, scanlines without compression: channels [(name, type 0 uint/1 half/2 float)],
    samples counting up; the data window's corner at (x0, y0)."""
    def attr(name, kind, value):
        return name.encode() + b'\0' + kind.encode() + b'\0' + struct.pack('<i', len(value)) + value
    chans = sorted(channels)
    chlist = b''.join(n.encode() + b'\0' + struct.pack('<iBxxxii', t, 0, 1, 1) for n, t in chans) + b'\0'
    box = struct.pack('<iiii', x0, y0, x0 + w - 1, y0 + h - 1)
    header = (b'\x76\x2f\x31\x01' + struct.pack('<I', 2) + attr('channels', 'chlist', chlist) +
              attr('compression', 'compression', b'\0') + attr('dataWindow', 'box2i', box) +
              attr('displayWindow', 'box2i', box) + attr('lineOrder', 'lineOrder', b'\0') +
              attr('pixelAspectRatio', 'float', struct.pack('<f', 1)) +
              attr('screenWindowCenter', 'v2f', struct.pack('<ff', 0, 0)) +
              attr('screenWindowWidth', 'float', struct.pack('<f', 1)) + b'\0')
    fmt = {0: '<I', 1: '<e', 2: '<f'}
    lines = []
    for y in range(h):
        data = b''.join(struct.pack(fmt[t], (y * w + x) % 7 + 1) for _, t in chans for x in range(w))
        lines.append(struct.pack('<ii', y0 + y, len(data)) + data)
    offsets, at = [], len(header) + 8 * h
    for l in lines:
        offsets.append(at)
        at += len(l)
    return header + b''.join(struct.pack('<Q', o) for o in offsets) + b''.join(lines)


def image_seeds(out):
    d = os.path.join(out, 'image')
    os.makedirs(d, exist_ok=True)
    w, h = 5, 3
    for name, ct, depth, ch in (('gray8', 0, 8, 1), ('grayalpha8', 4, 8, 2), ('rgb8', 2, 8, 3), ('rgba8', 6, 8, 4),
                                ('gray16', 0, 16, 1), ('rgb16', 2, 16, 3)):
        rows = [bytes((x * 37 + y * 11) & 0xFF for x in range(w * ch * depth // 8)) for y in range(h)]
        open(os.path.join(d, name + '.png'), 'wb').write(png(w, h, ct, depth, rows))
    rows = [bytes((x + y) % 3 for x in range(w)) for y in range(h)]
    open(os.path.join(d, 'palette.png'), 'wb').write(png(w, h, 3, 8, rows, bytes(range(9))))
    open(os.path.join(d, 'depth.exr'), 'wb').write(exr(w, h, [('Z', 2)]))
    open(os.path.join(d, 'ids.exr'), 'wb').write(exr(w, h, [('id', 0)]))
    open(os.path.join(d, 'rgba-half.exr'), 'wb').write(exr(w, h, [('R', 1), ('G', 1), ('B', 1), ('A', 1)], 2, -1))


def main():
    out = sys.argv[1]
    image_seeds(out)
    for d in ('bsp', 'pk3', 'glb'):
        os.makedirs(os.path.join(out, d), exist_ok=True)
    bsp = tiny_bsp()
    open(os.path.join(out, 'bsp', 'tiny.bsp'), 'wb').write(bsp)
    for name, method in (('deflated', zipfile.ZIP_DEFLATED), ('stored', zipfile.ZIP_STORED)):
        with zipfile.ZipFile(os.path.join(out, 'pk3', 'tiny-%s.pk3' % name), 'w', method) as z:
            for member, data in (('maps/readme.txt', b'hi'), ('maps/Tiny.bsp', bsp)):
                info = zipfile.ZipInfo(member, date_time=(2024, 1, 1, 0, 0, 0))
                info.compress_type = method
                z.writestr(info, data)
    for g in sys.argv[2:]:
        name = os.path.splitext(os.path.basename(g))[0]
        open(os.path.join(out, 'glb', name + '.glb'), 'wb').write(glb_from_gltf(g))


if __name__ == '__main__':
    main()
