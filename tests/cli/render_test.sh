#!/usr/bin/env bash
# tetcut render: a PNG of the size asked for, not blank, from a surface or a mesh with its
# wireframe; clear errors for a bad output name and for a wireframe with nothing to draw.
set -euo pipefail
source "$(dirname "$0")/lib.sh"

expect_exit 0 "$TETCUT" render --help
expect_stdout "--wireframe"

expect_exit 0 "$TETCUT" grid --cells 3 3 3 -o cube.vtu
printf 'v -1 -1 0.4\nv 2 -1 0.4\nv 2 2 0.4\nv -1 2 0.4\nf 1 2 3\nf 1 3 4\n' > z.obj
expect_exit 0 "$TETCUT" cut cube.vtu z.obj --out-mesh cut.vtu --out-surface cut.obj
expect_exit 0 "$TETCUT" render cut.obj -o pieces.png --pieces --size 320 200 --azimuth 20 --elevation 30
expect_exit 0 "$TETCUT" render cut.obj -o wire.png --wireframe cube.vtu --size 320 200
expect_exit 0 "$TETCUT" render cube.vtu -o mesh.png --wireframe --zoom 1.5
expect_stdout "edges"
# Cut cloth: what tetcut cut2d writes (the material, pieces coloured, its triangle copies over it),
# and a cloth scene's frames (the last one, or the one asked for, with its copies).
printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 0\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\n' > square.obj
printf 'v -1 0.3 0\nv 2 0.6 0\nl 1 2\n' > across.obj
expect_exit 0 "$TETCUT" cut2d square.obj across.obj -o material.vtp --copies copies.obj
expect_exit 0 "$TETCUT" render material.vtp -o cloth_cut.png --pieces --wireframe copies.obj --size 320 200 --elevation 90
expect_stdout "edges"
cat > cloth.json <<'JSON'
{"cloth": {"mesh": {"grid": {"cells": 4, "size": 1, "plane": "xz"}}},
 "pin": [{"box": [-1, -1, 0.99, 2, 1, 1.01]}],
 "time": {"dt": 0.01, "duration": 0.1, "output_every": 0.05},
 "cuts": [{"time": 0, "blade": {"poses": [[-1, -1, 0.4375, -1, 1, 0.4375], [2, -1, 0.4375, 2, 1, 0.4375]]}}],
 "output": {"picture": {"azimuth": -90, "elevation": 0, "zoom": 1.2, "size": [320, 240]}}}
JSON
expect_exit 0 "$TETCUT" sim cloth.json -o cloth --png
"$PYTHON" -c "import struct,sys; d=open(sys.argv[1],'rb').read(); assert struct.unpack('>II', d[16:24])==(320, 240)" \
  cloth/frame_0002.png || fail "the cloth's pictures are not the scene's size"
expect_exit 0 "$TETCUT" render cloth -o cloth_last.png --wireframe --pieces --azimuth -90 --elevation 0 --size 320 200
expect_stdout "surface_0002.vtp"
expect_stdout "edges"
expect_exit 0 "$TETCUT" render cloth -o cloth_plain.png --pieces --azimuth -90 --elevation 0 --size 320 200
cmp -s cloth_last.png cloth_plain.png && fail "the triangle copies are not drawn"
expect_exit 0 "$TETCUT" render cloth -o cloth_first.png --frame 0 --wireframe
expect_stdout "surface_0000.vtp"
expect_exit 2 "$TETCUT" render cloth -o x.png --frame 7
expect_stderr "the series has frames 0 to 2"
expect_exit 2 "$TETCUT" render material.vtp -o x.png --frame 1
expect_stderr "--frame goes with a directory"
"$PYTHON" - pieces.png wire.png mesh.png cloth_cut.png cloth_last.png <<'PY'
import struct, sys, zlib
def png(path):
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path
    width, height = struct.unpack(">II", data[16:24])
    # Decode the image data (8-bit RGB, one filter byte per row) to count non-background pixels.
    chunks, i = b"", 8
    while i < len(data):
        n, kind = struct.unpack(">I4s", data[i:i + 8])
        if kind == b"IDAT": chunks += data[i + 8:i + 8 + n]
        i += 12 + n
    raw = zlib.decompress(chunks)
    stride, rows, previous = 3 * width, [], bytearray(3 * width)
    for y in range(height):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - 3] if x >= 3 else 0
            b, c = previous[x], previous[x - 3] if x >= 3 else 0
            if f == 1: line[x] = (line[x] + a) & 255
            elif f == 2: line[x] = (line[x] + b) & 255
            elif f == 3: line[x] = (line[x] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c; pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line); previous = line
    covered = sum(1 for row in rows for x in range(0, stride, 3) if tuple(row[x:x + 3]) != (242, 242, 242))
    return width, height, covered / (width * height)
w, h, covered = png(sys.argv[1]); assert (w, h) == (320, 200) and covered > 0.1, (w, h, covered)
w, h, covered = png(sys.argv[2]); assert (w, h) == (320, 200) and covered > 0.1
w, h, covered = png(sys.argv[3]); assert (w, h) == (800, 600) and covered > 0.1
w, h, covered = png(sys.argv[4]); assert (w, h) == (320, 200) and covered > 0.1, covered
w, h, covered = png(sys.argv[5]); assert (w, h) == (320, 200) and covered > 0.05, covered
PY
# tetcut sim --png renders each output frame with a camera that holds still.
cat > drop.json <<'JSON'
{"mesh": {"grid": {"box": [0, 0, 0.1, 1, 1, 1.1], "cells": [2, 2, 2]}},
 "time": {"dt": 0.01, "duration": 0.1, "output_every": 0.05},
 "obstacles": [{"plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}}]}
JSON
expect_exit 0 "$TETCUT" sim drop.json -o frames --png
for f in 0 1 2; do
  "$PYTHON" -c "import struct,sys; d=open(sys.argv[1],'rb').read(); assert d[:8]==b'\x89PNG\r\n\x1a\n' and struct.unpack('>II', d[16:24])==(640, 480)" \
    frames/frame_000$f.png || fail "frame $f's picture is missing or the wrong size"
done
[[ ! -e frames/frame_0003.png ]] || fail "a picture beyond the last frame"
cmp -s frames/frame_0000.png frames/frame_0002.png && fail "the falling block looks the same in every frame"

# --animation assembles the frames with ffmpeg; ffprobe (from the same package) reads them back.
expect_exit 0 "$TETCUT" sim drop.json -o movie --animation drop.mp4
expect_stdout "drop.mp4 (3 frames at 20 per second)"
[[ $(ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=codec_name,width,height,nb_read_frames \
      -of csv=p=0 drop.mp4) == "h264,640,480,3" ]] || fail "drop.mp4 is not a 640x480 H.264 video of 3 frames"
expect_exit 0 "$TETCUT" sim drop.json -o gif --animation drop.gif --fps 5
[[ $(ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=codec_name,nb_read_frames,r_frame_rate \
      -of csv=p=0 drop.gif) == "gif,5/1,3" ]] || fail "drop.gif is not a GIF of 3 frames at 5 per second"
[[ -z $(ls -A | grep -E 'partial|ffmpeg.log') ]] || fail "temporary files left behind"
expect_exit 2 "$TETCUT" sim drop.json -o avi --animation drop.avi
expect_stderr "must be .mp4 or .gif"
[[ ! -e avi ]] || fail "a bad animation name still ran the scene"
# Without ffmpeg: a clear error, and no animation file.
expect_exit 2 env PATH=/nonexistent "$TETCUT" sim drop.json -o noffmpeg --animation none.mp4
expect_stderr "ffmpeg is not installed"
[[ ! -e none.mp4 ]] || fail "an animation appeared without ffmpeg"

expect_exit 2 "$TETCUT" render cut.obj -o picture.jpg
expect_stderr "must be a .png"
expect_exit 2 "$TETCUT" render cut.obj -o x.png --wireframe
expect_stderr "needs IN to be a tet mesh"
echo "render CLI: all checks passed"
