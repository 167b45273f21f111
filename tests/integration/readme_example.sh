#!/usr/bin/env bash
# Script glintd with curl: create a scene, start a session, upload paintings
# made by the glint CLI, fit them, follow the job, download the factors, a
# preview under a new light and the whole material package.
#
#   GLINT_URL  the daemon (default http://127.0.0.1:8080)
#   GLINT      the glint CLI (default: glint on the PATH, e.g. build/core/glint)
#   GLINT_KEY  the daemon's API key, if it runs with --api-key
#   OUT        where the files go (default ./glint-example)
# Needs curl and jq.
set -euo pipefail
URL=${GLINT_URL:-http://127.0.0.1:8080}
GLINT=${GLINT:-glint}
OUT=${OUT:-glint-example}
mkdir -p "$OUT"
api() { curl -sS --fail-with-body ${GLINT_KEY:+-H "Authorization: Bearer $GLINT_KEY"} "$@"; }

# 1. A scene: the built-in sphere seen from the 12 icosahedron views, 128x128.
scene=$(api -X POST "$URL/api/v1/scenes" -H 'Content-Type: application/json' \
            -d '{"mesh": "sphere", "width": 128, "height": 128}')
SCENE=$(jq -r .id <<<"$scene")
echo "scene    $SCENE ($(jq '.views | length' <<<"$scene") views)"

# 2. A painting session on it; the paint token grants writing.
session=$(api -X POST "$URL/api/v1/sessions" -H 'Content-Type: application/json' \
              -d "{\"scene_id\": \"$SCENE\"}")
SESSION=$(jq -r .id <<<"$session")
TOKEN=$(jq -r .paint_token <<<"$session")
echo "session  $SESSION (paint token $TOKEN)"

# 3. Paintings: here the CLI paints the same scene with a Cook-Torrance
#    material (an artist would paint them); the scene hashes must agree.
"$GLINT" scene create --size 128 -o "$OUT/scene.json" >/dev/null
[ "$("$GLINT" scene show "$OUT/scene.json" | jq -r .hash)" = "$(jq -r .hash <<<"$scene")" ]
"$GLINT" paint "$OUT/scene.json" --brdf 'ct:rough=0.3,kd=0.5,f0=0.3' --format png \
         -o "$OUT/paintings" >/dev/null
for f in "$OUT"/paintings/view_*.png; do
  k=${f##*view_}; k=$((10#${k%.png}))
  api -X PUT "$URL/api/v1/sessions/$SESSION/views/$k/painting" \
      -H "X-Glint-Token: $TOKEN" -H 'Content-Type: image/png' --data-binary @"$f" >/dev/null
done
echo "painted  $(ls "$OUT"/paintings/view_*.png | wc -l) views"

# 4. Fit: 201 with the material when the precomputation is cached, else 202
#    with a job to poll (or stream: curl -N "$URL/api/v1/jobs/ID/events?token=$TOKEN").
fit=$(api -X POST "$URL/api/v1/sessions/$SESSION/fits" -H "X-Glint-Token: $TOKEN" \
          -H 'Content-Type: application/json' -d '{"method": "hf3", "params": {"res": 64}}')
if JOB=$(jq -er .job.id <<<"$fit"); then
  while :; do
    job=$(api "$URL/api/v1/jobs/$JOB" -H "X-Glint-Token: $TOKEN")
    state=$(jq -r .job.state <<<"$job")
    echo "job      $JOB: $state, $(jq -r .job.stage <<<"$job") ($(jq -r .job.progress <<<"$job"))"
    case $state in
      done) MATERIAL=$(jq -r .job.material_id <<<"$job"); break ;;
      failed) echo "fit failed: $(jq -r .job.error <<<"$job")" >&2; exit 1 ;;
    esac
    sleep 0.2
  done
else
  MATERIAL=$(jq -r .id <<<"$fit")
fi

# 5. The material: its description, factor textures, a preview for a camera
#    and light never painted, and everything as one tar package.
M="$URL/api/v1/materials/$MATERIAL"
api "$M" -H "X-Glint-Token: $TOKEN" -o "$OUT/material.json"
echo "material $MATERIAL: rms error on the painted pixels" \
     "$(jq .errors.rms_painted "$OUT/material.json"), precomputation" \
     "$(jq .precomputation.cache.cold_seconds "$OUT/material.json") s"
api "$M/factors.png" -H "X-Glint-Token: $TOKEN" -o "$OUT/factors.png"
api "$M/factors.exr" -H "X-Glint-Token: $TOKEN" -o "$OUT/factors.exr"
api "$M/preview.png?eye=0,3,1&light=2,2,2&size=256" -H "X-Glint-Token: $TOKEN" \
    -o "$OUT/preview.png"
api "$M/package" -H "X-Glint-Token: $TOKEN" -o "$OUT/material.tar"
echo "files    $OUT/{material.json,factors.png,factors.exr,preview.png,material.tar}"
