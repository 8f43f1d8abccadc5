#!/usr/bin/env python3
"""Writes pbrt-scenes/verify/v3-textures.pbrt (no argument) or v4-textures.pbrt (`v4`)
to standard output: a 4x4 wall of quads, one texture class or mapping per tile, lit by
a uniform sky, so each tile of the image shows its texture's values.

    python3 tools/verify_textures.py    > pbrt-scenes/verify/v3-textures.pbrt
    python3 tools/verify_textures.py v4 > pbrt-scenes/verify/v4-textures.pbrt
"""
import sys, re
v4 = len(sys.argv) > 1 and sys.argv[1] == 'v4'
col = 'rgb' if v4 else 'color'
pt = 'point3' if v4 else 'point'
out = []
w = out.append
ver = 'pbrt-v4' if v4 else 'pbrt-v3'
w(f"# {ver}'s procedural textures and mappings, one per tile of a 4x4 wall lit by a")
w("# uniform sky, so each tile shows its texture's values. Checked against " + ver + " (tests/it/pbrt_refs.rs).")
w('LookAt 0 0 -5  0 0 0  0 1 0')
w('Camera "orthographic"')
w(f'Film "{"rgb" if v4 else "image"}" "integer xresolution" 128 "integer yresolution" 128 "string filename" "{"v4" if v4 else "v3"}-textures.exr"')
if v4:
    w('PixelFilter "box" "float xradius" .5 "float yradius" .5  # as pbrt-sppm: no filter-importance jitter')
    w('Sampler "halton" "integer pixelsamples" 64  # pbrt-v4: one SPPM iteration per pixel sample')
    w('Integrator "sppm" "integer photonsperiteration" 10000 "float radius" 0.05 "integer maxdepth" 2')
else:
    w('Integrator "sppm" "integer numiterations" 16 "integer photonsperiteration" 10000 "float radius" 0.05 "integer maxdepth" 2')
w('WorldBegin')
w(f'LightSource "infinite" "{col} L" [1 1 1]')
tiles = [
 # (name, texture statements, material Kd texture)
 ('dots', ['Texture "t" "spectrum" "dots" "float uscale" 6 "float vscale" 6 "'+col+' inside" [.9 .2 .1] "'+col+' outside" [.1 .3 .8]']),
 # fBm goes below 0: the mix then leaves [0, 1], where pbrt-v4 clamps each wavelength
 # and RGB each channel, so v4's scene mixes greys.
 ('fbm', ['Texture "a" "float" "fbm" "float roughness" .6', 'Texture "t" "spectrum" "mix" "texture amount" "a" "'+col+' tex1" ' + ('[.2 .2 .2] "'+col+' tex2" [.8 .8 .8]' if v4 else '[.1 .1 .9] "'+col+' tex2" [.9 .9 .1]')]),
 ('wrinkled', ['Texture "a" "float" "wrinkled" "integer octaves" 6', 'Texture "t" "spectrum" "mix" "texture amount" "a" "'+col+' tex1" [.1 .8 .1] "'+col+' tex2" [.8 .1 .8]']),
 ('windy', ['Scale 4 4 4', 'Texture "a" "float" "windy"', 'Texture "t" "spectrum" "mix" "texture amount" "a" "'+col+' tex1" [.5 .5 .5] "'+col+' tex2" [.9 .1 .1]']),
 # pbrt-v3's marble evaluates its colour spline outside [0, 1] (a DEVIATION in pbrt-sppm),
 # so v3's scene has another fBm there.
 ('marble', ['Texture "t" "spectrum" "marble" "float scale" 6 "float variation" .5'] if v4 else ['Rotate 60 1 1 0', 'Scale 3 3 3', 'Texture "t" "spectrum" "fbm" "integer octaves" 5']),
 ('checker3d', ['Scale .1 .1 .1', 'Texture "t" "spectrum" "checkerboard" "integer dimension" 3 "'+col+' tex1" [.9 .9 .9] "'+col+' tex2" [.2 .2 .6]']),
 ('uv' if not v4 else 'dirmix', ['Texture "t" "spectrum" "uv" "float uscale" 2 "float vscale" 3'] if not v4 else ['Texture "c" "spectrum" "checkerboard" "float uscale" 4 "float vscale" 4', 'Texture "t" "spectrum" "directionmix" "vector3 dir" [0 .6 -.8] "texture tex1" "c" "'+col+' tex2" [.9 .5 .1]']),
 ('bilerp', ['Texture "t" "spectrum" "bilerp" "'+col+' v00" [.9 .1 .1] "'+col+' v01" [.1 .9 .1] "'+col+' v10" [.1 .1 .9] "'+col+' v11" [.9 .9 .9]']),
 ('planar', ['Rotate 30 0 0 1', 'Texture "t" "spectrum" "checkerboard" "string mapping" "planar" "' + ('vector3' if v4 else 'vector') + ' v1" [5 0 0] "' + ('vector3' if v4 else 'vector') + ' v2" [0 5 0] "float udelta" .25 "'+col+' tex1" [.8 .8 .2] "'+col+' tex2" [.2 .2 .2]']),
 ('spherical', ['Translate 0 0 1', 'Texture "t" "spectrum" "checkerboard" "string mapping" "spherical" "'+col+' tex1" [.9 .3 .3] "'+col+' tex2" [.3 .3 .9]']),
 ('cylindrical', ['Texture "t" "spectrum" "uv" "string mapping" "cylindrical"'] if not v4 else ['Texture "t" "spectrum" "bilerp" "string mapping" "cylindrical"  "'+col+' v00" [.1 .1 .1] "'+col+' v01" [.2 .8 .2] "'+col+' v10" [.8 .3 .2] "'+col+' v11" [.8 .8 .2]']),
 ('scale', ['Texture "d" "spectrum" "dots" "float uscale" 4 "float vscale" 4', 'Texture "f" "' + ('float' if v4 else 'spectrum') + '" "fbm" "integer octaves" 3', 'Texture "t" "spectrum" "scale" ' + ('"texture tex" "d" "texture scale" "f"' if v4 else '"texture tex1" "d" "texture tex2" "f"')]),
 ('dotsfloat', ['Texture "a" "float" "dots" "float uscale" 3 "float vscale" 3 "float inside" .2 "float outside" .8', 'Texture "t" "spectrum" "mix" "texture amount" "a" "'+col+' tex1" [.9 .6 .1] "'+col+' tex2" [.1 .6 .9]']),
 ('marble2', ['Rotate 60 1 1 0', 'Texture "t" "spectrum" "marble" "float scale" 3 "float variation" 1 "integer octaves" 4'] if v4 else ['Rotate 60 1 1 0', 'Texture "t" "spectrum" "checkerboard" "integer dimension" 3 "'+col+' tex1" [.9 .6 .3] "'+col+' tex2" [.3 .6 .9]']),
 ('checker2d', ['Texture "t" "spectrum" "checkerboard" "float uscale" 5 "float vscale" 3 "float udelta" .3 "'+col+' tex1" [.9 .9 .9] "'+col+' tex2" [.1 .1 .1]']),
 ('wrinkledspec', ['Translate .3 .2 0'] + (['Texture "a" "float" "wrinkled" "float roughness" .4', 'Texture "t" "spectrum" "scale" "rgb tex" [.9 .7 .5] "texture scale" "a"'] if v4 else ['Texture "t" "spectrum" "wrinkled" "float roughness" .4'])),
]
assert len(tiles) == 16
for i, (name, texs) in enumerate(tiles):
    r, c = divmod(i, 4)
    # tile (r, c): column c from the left of the image, row r from the top.
    x0 = -1 + 0.5 * c
    y0 = 1 - 0.5 * (r + 1)
    w(f'AttributeBegin  # {name}')
    for t in texs:
        t = re.sub(r'"(t|a|c|d|f)"', lambda m: f'"{m.group(1)}{i}"', t)
        w('  ' + t)
    if any(t.split()[0] in ('Scale', 'Rotate', 'Translate') for t in texs):
        w('  Identity  # the texture statements above saw the transform; the shape does not')
    w(f'  Material "diffuse" "texture reflectance" "t{i}"' if v4 else f'  Material "matte" "texture Kd" "t{i}"')
    w('  AttributeEnd') if False else None
    P = f'{x0} {y0} 0  {x0+0.5} {y0} 0  {x0+0.5} {y0+0.5} 0  {x0} {y0+0.5} 0'
    w('  Shape "trianglemesh" "' + pt + f' P" [{P}] "integer indices" [0 1 2 0 2 3] ' + ('"point2 uv"' if v4 else '"float uv"') + ' [0 0 1 0 1 1 0 1]')
    w('AttributeEnd')
w('WorldEnd') if not v4 else None
print('\n'.join(out))
