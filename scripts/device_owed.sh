#!/usr/bin/env bash
# The GPU figures still owed at the end of 2026-12-08's session, in one device call of about
# 6 minutes (issues 52, 55, 56, 58): the merged kernels build on the card and the two kernels
# agree (PNG mean difference), the denoiser's speed at 1080p, its quality on HotelRoom and
# FlightHelmet at 640x360 against 16k-spp references, adaptive sampling (both rules) on the card,
# and the two-level in-place animation update.
#
# Here: build, then fill .device (ignored; name it in `carry`, 64 MiB with the repository):
#   mkdir -p .device/scenes/HotelRoom .device/scenes/khronos
#   strip -o /tmp/p target/release/penumbra && xz -T2 -9 -c /tmp/p > .device/penumbra.xz
#   S=$PENUMBRA_SCENES; cp -r $S/FlightHelmet $S/DreamApartment $S/CornellBox $S/Fox .device/scenes/
#   cp $S/HotelRoom/hotel-room.glb .device/scenes/HotelRoom/
#   cp -r $S/khronos/TransmissionRoughnessTest $S/khronos/IridescenceSuzanne .device/scenes/khronos/
#   cp scripts/device_owed.sh .device/
# There: OUT=$OUT bash .device/device_owed.sh   (log.txt, CSVs and PNGs under $OUT)
set -uo pipefail
D=.device; S=$D/scenes; P=/tmp/penumbra
[ -x $P ] || { xz -dc $D/penumbra.xz > $P && chmod +x $P; }
L=$OUT/log.txt; T0=$SECONDS; TMP=/tmp/owed; mkdir -p $TMP
log() { echo "[$((SECONDS-T0))s] $*" | tee -a $L; }
step() { local lim=$1; shift; log "+ $*"; timeout $lim "$@" >>$L 2>&1; log "  rc $? ($((SECONDS-T0))s)"; }
adaptive() { local sc=$1 n=$2; shift 2
  [ -s $TMP/ref-$n.exr ] || step 120 $P render $sc "$@" --device gpu --width 640 --height 480 --spp 8192 --seed 999 -o $TMP/ref-$n.exr
  for rt in error:0.02 error:0.05 cost:$CT; do
    step 100 $P bench converge $sc "$@" --device gpu --width 640 --height 480 --reference $TMP/ref-$n.exr --configs mis+rr --spp 1024 --adaptive ${rt#*:} --adaptive-rule ${rt%%:*} --max-seconds 100000 --csv $OUT/adaptive-$n-${rt%%:*}-${rt#*:}.csv
  done; }
quality() { local sc=$1 n=$2
  [ -s $TMP/dref-$n.exr ] || step 150 $P render $sc --device gpu --width 640 --height 360 --spp 16384 --seed 1000 -o $TMP/dref-$n.exr
  step 100 $P bench converge $sc --device gpu --width 640 --height 360 --reference $TMP/dref-$n.exr --configs mis+rr --spp 256 --seed 1 --denoise --denoiser full --max-seconds 100000 --csv $OUT/denoise-$n-full.csv
  step 100 $P bench converge $sc --device gpu --width 640 --height 360 --reference $TMP/dref-$n.exr --configs mis+rr --spp 256 --seed 1 --denoise --denoiser large --max-seconds 100000 --csv $OUT/denoise-$n-large.csv; }

nvidia-smi --query-gpu=name,driver_version --format=csv >>$L 2>&1
step 30 $P devices
# 1. every kernel builds on the card; wavefront and megakernel agree (PNG mean difference)
mkdir -p $OUT/img
for sc in assets/cornell-box.glb $S/khronos/TransmissionRoughnessTest/glTF-Binary/*.glb $S/khronos/IridescenceSuzanne/glTF-Binary/*.glb $S/DreamApartment/dream-apartment.glb; do
  n=$(basename ${sc%.*})
  for k in wavefront megakernel; do
    step 90 $P render $sc --device gpu --kernel $k --width 320 --height 240 --spp 256 -o $OUT/img/$n-$k.png
  done
  python3 - $OUT/img/$n-wavefront.png $OUT/img/$n-megakernel.png >>$L 2>&1 <<'PY'
import sys, numpy as np
from PIL import Image
a, b = (np.asarray(Image.open(p).convert('RGB'), dtype=np.float64) for p in sys.argv[1:3])
print(f"{sys.argv[1].split('/')[-1]}: wavefront vs megakernel mean |diff| {np.abs(a-b).mean():.3f} of 255, mean {a.mean():.2f} / {b.mean():.2f}")
PY
done
step 30 $P render $S/khronos/TransmissionRoughnessTest/glTF-Binary/*.glb --device gpu --denoise --width 640 --height 480 --spp 64 -o $OUT/img/trt-denoised.png
# 2. the denoiser's speed after 8b25bbc
for q in full small; do step 60 $P bench denoise --device gpu --width 1920 --height 1080 --quality $q --runs 5 --oidn-device none; done
# 3. quality: FlightHelmet and HotelRoom at 640x360 against 16k refs
quality $S/HotelRoom/hotel-room.glb hotel
quality $S/FlightHelmet/FlightHelmet.gltf helmet
# 4. adaptive on the card: HotelRoom, FlightHelmet, the box
CT=0.01 adaptive $S/FlightHelmet/FlightHelmet.gltf helmet --env studio
CT=0.02 adaptive $S/HotelRoom/hotel-room.glb hotel
CT=0.003 adaptive assets/cornell-box.glb box
# 5. animation on two levels (written in place)
step 60 $P bench animation $S/Fox/Fox.glb --clip Run --bvh two-level --frames 60 --device gpu
log done
