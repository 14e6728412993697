#!/usr/bin/env bash
# Make sure `linux` (user-mode Linux, for the vcan tests) boots on this host.
#
# Debian bookworm's user-mode-linux (6.1) and trixie's (6.12) panic at their first process on
# CPUs with AMX (Intel Sapphire Rapids and later): "userspace - ptrace set fp regs failed,
# errno = 14" (their XSAVE buffer is smaller than the host's). Debian unstable's (7.x) sizes
# it from the host and boots. It needs a newer C library than bookworm's, so it runs with
# unstable's own loader and libc, unpacked beside it; its modules go where the test harness
# looks (/usr/lib/uml/modules/VERSION, the newest version wins).
set -euo pipefail

boots() {
    local dir
    dir=$(mktemp -d)
    printf '#!/bin/sh\necho UML-BOOTED\nhalt -f\n' > "$dir/init.sh"
    chmod +x "$dir/init.sh"
    timeout 120 linux mem=256M rootfstype=hostfs rw "init=$dir/init.sh" con=null \
        con0=fd:0,fd:1 < /dev/null 2>&1 | grep -q UML-BOOTED
}

if boots; then
    exit 0
fi
echo "user-mode Linux $(dpkg-query -W -f='${Version}' user-mode-linux) does not boot on" \
     "this CPU; installing Debian unstable's" >&2
root=/opt/uml-unstable
rm -rf "$root"
mkdir -p "$root/lists/partial" "$root/debs"
cat > "$root/sid.sources" <<'EOF'
Types: deb
URIs: http://deb.debian.org/debian
Suites: sid
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
EOF
apt_sid=(-o "Dir::Etc::SourceList=$root/sid.sources" -o Dir::Etc::SourceParts=/dev/null
         -o "Dir::State::Lists=$root/lists" -o APT::Sandbox::User=root)
if ! command -v patchelf > /dev/null; then
    apt-get update -qq
    apt-get install -y -qq patchelf > /dev/null
fi
apt-get "${apt_sid[@]}" update -qq
(cd "$root/debs" && apt-get "${apt_sid[@]}" download -qq user-mode-linux libc6)
dpkg -x "$root"/debs/user-mode-linux_*.deb "$root/uml"
dpkg -x "$root"/debs/libc6_*.deb "$root/libc"
mkdir -p "$root/lib"
cp "$root"/libc/usr/lib/x86_64-linux-gnu/{ld-linux-x86-64.so.2,libc.so.6,libm.so.6} "$root/lib/"
install -m 755 "$root/uml/usr/bin/linux.uml" "$root/linux.uml"
patchelf --set-interpreter "$root/lib/ld-linux-x86-64.so.2" --set-rpath "$root/lib" \
    "$root/linux.uml"
# `linux` is Debian's alternative (/usr/bin/linux): point it at this kernel
update-alternatives --quiet --install /usr/bin/linux linux "$root/linux.uml" 200
update-alternatives --quiet --set linux "$root/linux.uml"
cp -r "$root"/uml/usr/lib/uml/modules/* /usr/lib/uml/modules/
rm -rf "$root/debs" "$root/uml" "$root/libc"
hash -r
if ! boots; then
    echo "Debian unstable's user-mode Linux does not boot either" >&2
    exit 1
fi
