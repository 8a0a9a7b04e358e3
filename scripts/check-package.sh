#!/usr/bin/env bash
# ctest's check of the .deb that scripts/package.sh makes (once: the board VM
# installs the same file; made here if it is missing or older than what it
# packs): it holds the binary,
# the unit, the service's user, the conffiles in /etc/probelight, the board
# notes, the copyright, changelog and manual page; its maintainer scripts are
# valid shell and leave systemctl to deb-systemd-helper/-invoke; and lintian
# finds no error or warning in it.
set -euo pipefail
build_dir=$(cd "$1" && pwd)
"$(dirname "$0")/package.sh" "$build_dir" >/dev/null
cd "$build_dir"
deb=$(ls probelight_*.deb)
contents=$(dpkg-deb -c "$deb" | awk '{print $6}')
status=0
for path in ./usr/bin/probelight ./usr/lib/systemd/system/probelight.service ./usr/lib/sysusers.d/probelight.conf \
            ./etc/probelight/probelight.yaml ./etc/probelight/camera.yaml ./etc/probelight/rig.yaml \
            ./usr/share/doc/probelight/raspberry-pi.md ./usr/share/doc/probelight/config.txt \
            ./usr/share/doc/probelight/probelight.yaml ./usr/share/probelight/models/ceramic-bowl.glb \
            ./usr/share/doc/probelight/copyright ./usr/share/doc/probelight/changelog.gz \
            ./usr/share/man/man1/probelight.1.gz; do
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
# The unit's enablement goes through deb-systemd-helper, whose state purge
# undoes; systemctl only reloads.
grep -q 'deb-systemd-helper enable probelight.service' "$control/postinst" || { echo "postinst does not enable through deb-systemd-helper"; status=1; }
grep -q 'deb-systemd-helper purge probelight.service' "$control/postrm" || { echo "postrm does not purge through deb-systemd-helper"; status=1; }
if grep -n 'systemctl' "$control"/postinst "$control"/prerm "$control"/postrm | grep -v 'systemctl --system daemon-reload'; then
  echo "maintainer scripts call systemctl for more than daemon-reload"; status=1
fi
depends=$(dpkg-deb -f "$deb" Depends)
for needed in libgpiod2 libsystemd0 libegl-mesa0 libapriltag3; do
  grep -q "$needed" <<<"$depends" || { echo "Depends lacks $needed: $depends"; status=1; }
done
# Debian's own checker: errors and warnings fail (info tags are advice).
if command -v lintian >/dev/null; then
  findings=$(lintian --tag-display-limit 0 "$deb" 2>&1 | grep -E '^[EW]: ' || true)
  [ -z "$findings" ] || { echo "lintian:"; echo "$findings"; status=1; }
else
  echo "lintian not installed (scripts/install-deps.sh installs it): not run"; status=1
fi
[ "$status" = 0 ] && echo "package ok: $deb"
exit "$status"
