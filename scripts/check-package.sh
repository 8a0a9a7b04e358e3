#!/usr/bin/env bash
# ctest's check of the .deb (scripts/package.sh): it builds, holds the binary,
# the unit, the service's user, the conffiles in /etc/probelight and the
# board notes, and its maintainer scripts are valid shell.
set -euo pipefail
build_dir=$1
cd "$build_dir"
rm -f probelight_*.deb
cpack -G DEB > cpack.log 2>&1 || { cat cpack.log; exit 1; }
deb=$(ls probelight_*.deb)
contents=$(dpkg-deb -c "$deb" | awk '{print $6}')
status=0
for path in ./usr/bin/probelight ./usr/lib/systemd/system/probelight.service ./usr/lib/sysusers.d/probelight.conf \
            ./etc/probelight/probelight.yaml ./etc/probelight/camera.yaml ./etc/probelight/rig.yaml \
            ./usr/share/doc/probelight/raspberry-pi.md ./usr/share/doc/probelight/config.txt \
            ./usr/share/doc/probelight/probelight.yaml ./usr/share/probelight/models/ceramic-bowl.glb; do
  grep -qx -- "$path" <<<"$contents" || { echo "missing from $deb: $path"; status=1; }
done
control=$(mktemp -d)
trap 'rm -rf "$control"' EXIT
dpkg-deb -e "$deb" "$control"
for conffile in /etc/probelight/probelight.yaml /etc/probelight/camera.yaml /etc/probelight/rig.yaml; do
  grep -qx -- "$conffile" "$control/conffiles" || { echo "not a conffile: $conffile"; status=1; }
done
for script in postinst prerm postrm; do
  sh -n "$control/$script" || { echo "$script: not valid shell"; status=1; }
done
depends=$(dpkg-deb -f "$deb" Depends)
for needed in libgpiod2 libsystemd0 libegl-mesa0 libapriltag3; do
  grep -q "$needed" <<<"$depends" || { echo "Depends lacks $needed: $depends"; status=1; }
done
[ "$status" = 0 ] && echo "package ok: $deb"
exit "$status"
