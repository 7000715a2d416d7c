#!/usr/bin/env bash
# The project file through the CLI: fit writes it, `project info` reads it,
# `project export` re-exports without fitting (the fit's level to within its
# rounding), `texture --project` textures it as the page does and saves it,
# `project refit` fits the kept scan again (with new axes too), `likeness photos` keeps its photos and points in
# its project and `project info --extract-photos` gives them back (two of the same name
# both, one renamed), and a cut or foreign file is
# refused with exit 1 and a reason.
# Usage: cli_project.sh LIKENESS WORKDIR
set -euo pipefail
L="$1"; W="$2"
rm -rf "$W"; mkdir -p "$W"; cd "$W"
"$L" synth-scan --seed 2 --points 60000 --out . > /dev/null
"$L" fit --scan scan.ply --out fit --levels 2 --scan-frame --project head.likeness.glb > fit.log
grep -q "wrote head.likeness.glb" fit.log
"$L" project info head.likeness.glb > info.txt
grep -q "level 2: [0-9]* vertices" info.txt
grep -q "texture: none" info.txt
"$L" project export head.likeness.glb --level 2 --scan-frame --out l2.obj > /dev/null
python3 - <<'PY'
a = [list(map(float, l.split()[1:])) for l in open("l2.obj") if l.startswith("v ")]
b = [list(map(float, l.split()[1:])) for l in open("fit/level2.obj") if l.startswith("v ")]
assert len(a) == len(b) and len(a) > 1000, (len(a), len(b))
worst = max(abs(x - y) for p, q in zip(a, b) for x, y in zip(p, q))
assert worst < 1e-12, worst  # the fit's own state and an evaluation differ by rounding
fa = [l for l in open("l2.obj") if l.startswith("f ")]
fb = [l for l in open("fit/level2.obj") if l.startswith("f ")]
assert fa == fb
print("export matches the fit's level 2 within", worst)
PY
"$L" texture --project head.likeness.glb --make-synthetic photos --photo-width 480 --photo-height 360 > /dev/null
"$L" texture --project head.likeness.glb --photos photos/photo{0,1,2}.png --points photos/points{0,1,2}.txt \
  --out tex --size 256 --project-out textured.likeness.glb > tex.log
"$L" project info textured.likeness.glb | grep -q "texture: 256x256 skin"
"$L" project export textured.likeness.glb --format textured --scan-frame --out head.obj > /dev/null
cmp <(grep '^vt' head.obj) <(grep '^vt' tex/textured.obj)
cmp <(grep '^v ' head.obj) <(grep '^v ' tex/textured.obj)
# refit: the kept scan fitted again with the project's options gives the
# same alignment and fits as the original (the project keeps the scan's
# points and triangles; its normals, which only the displacements read, not).
"$L" project refit head.likeness.glb --out refit.likeness.glb > refit.log
"$L" project info refit.likeness.glb > refit_info.txt
grep -q "level 2: [0-9]* vertices" refit_info.txt
for stage in initial_alignment local_fitting global_fitting; do
  cmp <(grep "^  $stage" info.txt) <(grep "^  $stage" refit_info.txt)
done
"$L" project refit head.likeness.glb --levels 1 --out refit1.likeness.glb > /dev/null
"$L" project info refit1.likeness.glb | grep -q "level 1: [0-9]* vertices"
if "$L" project info refit1.likeness.glb | grep -q "level 2:"; then echo "--levels 1 kept level 2"; exit 1; fi
# --up/--facing reach the refit: told the upright scan lies with +z up, the
# fit finds it does not and turns it back, saying so; a zero direction is
# refused as a usage error.
"$L" project refit head.likeness.glb --levels 1 --up +z --facing -y --out refit_axes.likeness.glb > axes.log
grep -q "note: the scan seems to face +z with +y up" axes.log
if grep -q "seems to face" refit.log; then echo "the plain refit turned the scan"; exit 1; fi
set +e; "$L" project refit head.likeness.glb --up 0 0 0 --out bad.likeness.glb 2> err.txt; rc=$?; set -e
[ "$rc" = 2 ] && grep -q "take an axis" err.txt && [ ! -e bad.likeness.glb ]
head -c 4000 head.likeness.glb > cut.glb
if "$L" project info cut.glb 2> err.txt; then echo "a cut file was read"; exit 1; fi
grep -q "truncated Likeness project" err.txt
if "$L" project info scan.ply 2> err.txt; then echo "a PLY was read as a project"; exit 1; fi
grep -q "not a Likeness project" err.txt
# photos: `likeness photos` keeps its photos and points files in the project
# (version 3); `project info --extract-photos` writes them out byte for byte,
# and `likeness photos` on the extracted files makes the same head again.
"$L" synth-photos --seed 4 --cameras 5 --out sp > /dev/null
"$L" photos --points sp/view_0{0..4}.json --photos sp/view_0{0..4}.png --map sp/map.json --levels 1 --no-texture \
  --out ph1 > ph1.log
"$L" project info ph1/head.likeness.glb --extract-photos kept > kept.log
grep -q "Likeness project, version 3" kept.log
grep -q "photo view_00.png: face, PNG" kept.log
for i in 0 1 2 3 4; do
  cmp kept/view_0$i.png sp/view_0$i.png
  cmp kept/view_0$i.png.points.json sp/view_0$i.json
done
grep -q "make the head again: likeness photos --photos kept/view_00.png" kept.log
"$L" photos --points kept/view_0{0..4}.png.points.json --photos kept/view_0{0..4}.png --map sp/map.json --levels 1 \
  --no-texture --out ph2 > ph2.log
cmp ph1/control.obj ph2/control.obj
# Two photos of the same name from different folders: neither overwrites
# the other; the later one is written as K_NAME and the line says so.
mkdir -p other && cp sp/view_01.png other/view_00.png
"$L" photos --points sp/view_0{0,1,2}.json --photos sp/view_00.png other/view_00.png sp/view_02.png --map sp/map.json \
  --levels 1 --no-texture --out ph3 > ph3.log
"$L" project info ph3/head.likeness.glb --extract-photos same > same.log
cmp same/view_00.png sp/view_00.png
cmp same/view_00.png.points.json sp/view_00.json
cmp same/2_view_00.png sp/view_01.png
cmp same/2_view_00.png.points.json sp/view_01.json
cmp same/view_02.png sp/view_02.png
grep -q "wrote same/2_view_00.png (face; photo 2, named view_00.png like an earlier one: renamed" same.log
grep -q "make the head again: likeness photos --photos same/view_00.png same/2_view_00.png same/view_02.png" same.log
if "$L" project info head.likeness.glb --extract-photos none 2> err.txt; then echo "a project without photos extracted some"; exit 1; fi
grep -q "keeps no photos" err.txt
echo "cli project: ok"
