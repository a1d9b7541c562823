#!/usr/bin/env bash
# Install the tools the interoperability and storage tests need:
#   * tshark      (Debian package; its iec60870_104 / iec60870_asdu dissectors
#                  check captures of our traffic)
#   * c104        (PyPI; Python bindings of lib60870-C, the independent 104 peer
#                  used by tests/peer/c104_server.py and c104_client.py)
#   * postgresql  (Debian package; the server binaries with which
#                  scripts/with-postgres.sh runs a throwaway cluster for the
#                  event store's PostgreSQL tests)
#   * chromium    (Debian packages chromium, chromium-driver and a font,
#                  fonts-dejavu-core; the web HMI's browser tests,
#                  crates/hmi/tests/browser.rs, drive headless Chromium
#                  through chromedriver over WebDriver)
#   * aiosmtpd    (PyPI; the loopback SMTP server the notify crate's e-mail
#                  tests start, tests/support/smtp_sink.py)
#   * mosquitto   (Debian package; the MQTT broker the Sparkplug B tests start on a
#                  free loopback port, crates/sparkplug/tests/broker.rs and
#                  crates/stanice/tests/cli/sparkplug.rs)
#   * paho-mqtt, tahu, protobuf (PyPI; the independent Sparkplug B consumer
#                  crates/sparkplug/tests/consumer.py: paho's MQTT client and
#                  Eclipse Tahu's published sparkplug_b protobuf, which pins
#                  protobuf 3.19.1)
#   * iproute2    (Debian package; `ip` makes the network namespaces of
#                  scripts/netns-station.sh, crates/stanice/tests/netns.rs)
#   * hat-drivers (PyPI; its IEC 60870-5-103 master, FT1.2 link layer and
#                  serial driver are the independent 103 peer of
#                  tests/peer/hat103_master.py, used by
#                  crates/stanice/tests/iec103_hat.rs against our relay)
#
# Choice of Python environment: c104 is installed with pip into the machine's
# own python3 (no venv). c104 ships a manylinux wheel for CPython 3.11 on
# x86_64, so nothing is compiled and no build dependencies are needed. A venv
# would only add an activation step to every CI command; the tests call plain
# `python3`. If a future machine lacks a wheel, pip falls back to the sdist,
# which needs cmake and a C++ compiler: we install those (Debian packages
# cmake, g++) only in that case.
#
# Safe to run repeatedly: every step checks first and does nothing when the
# pinned version is already there. Non-interactive (CI=true, no stdin).
#
# Usage: bash scripts/install-test-deps.sh
set -euo pipefail

C104_VERSION="2.2.1"   # verified against tests/peer/*.py (see tests/peer/README.md)
AIOSMTPD_VERSION="1.4.6"   # verified against tests/support/smtp_sink.py
PYSERIAL_VERSION="3.5"   # pymodbus's RTU over a pseudo-terminal
PYMODBUS_VERSION="3.16.1"   # the Modbus TCP/RTU peer of the field I/O tests
PYTHON_SNAP7_VERSION="3.3.0"   # the S7 peer (Snap7 server and client) of the field I/O tests
HAT_DRIVERS_VERSION="0.10.10"   # verified against tests/peer/hat103_master.py
PAHO_MQTT_VERSION="2.2.0"   # verified against crates/sparkplug/tests/consumer.py
TAHU_VERSION="0.1.2"   # its sparkplug_b_pb2, the consumer's protobuf
PROTOBUF_VERSION="3.19.1"   # the one tahu 0.1.2 requires
PYTHON="${PYTHON:-python3}"

export DEBIAN_FRONTEND=noninteractive
export PIP_DISABLE_PIP_VERSION_CHECK=1
export PIP_ROOT_USER_ACTION=ignore

log() { echo "[install-test-deps] $*"; }

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then SUDO="sudo -n"; else
        log "not root and no sudo: cannot install Debian packages"; fi
fi

APT_UPDATED=0
apt_update_once() {
    if [ "$APT_UPDATED" -eq 0 ]; then
        log "apt-get update"
        $SUDO apt-get update -qq
        APT_UPDATED=1
    fi
}

apt_install() {
    # apt_install PKG...: installs only the packages that are missing.
    local missing=()
    for p in "$@"; do
        if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
            missing+=("$p")
        fi
    done
    if [ "${#missing[@]}" -eq 0 ]; then
        log "already installed: $*"
        return 0
    fi
    apt_update_once
    log "apt-get install ${missing[*]}"
    $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}" </dev/null
}

# ---------------------------------------------------------------- tshark
if command -v tshark >/dev/null 2>&1; then
    log "tshark present: $(tshark --version 2>/dev/null | head -n1)"
else
    # wireshark-common asks whether non-root users may capture; answer "no"
    # up front so the install never prompts.
    echo "wireshark-common wireshark-common/install-setuid boolean false" \
        | $SUDO debconf-set-selections
    apt_install tshark
    log "tshark installed: $(tshark --version 2>/dev/null | head -n1)"
fi

# ---------------------------------------------------------------- c104
c104_installed_version() {
    "$PYTHON" - <<'EOF' 2>/dev/null || true
import importlib.metadata as m
try:
    import c104  # noqa: F401  (the import itself must work, not only the metadata)
    print(m.version("c104"))
except Exception:
    pass
EOF
}

have="$(c104_installed_version)"
if [ "$have" = "$C104_VERSION" ]; then
    log "c104 $have present"
else
    log "c104 present: '${have:-none}', want $C104_VERSION"
    if ! "$PYTHON" -m pip install -q --only-binary=:all: "c104==$C104_VERSION"; then
        log "no binary wheel for this platform; building c104 from source"
        apt_install cmake g++ make
        "$PYTHON" -m pip install -q "c104==$C104_VERSION"
    fi
    have="$(c104_installed_version)"
    if [ "$have" != "$C104_VERSION" ]; then
        log "ERROR: c104 $C104_VERSION did not install (found '${have:-none}')"
        exit 1
    fi
    log "c104 $have installed"
fi

# ---------------------------------------------------------------- aiosmtpd
# Pure Python (a py3-none-any wheel): nothing to compile.
aiosmtpd_installed_version() {
    "$PYTHON" - <<'EOF' 2>/dev/null || true
import importlib.metadata as m
try:
    import aiosmtpd.smtp  # noqa: F401  (the import itself must work, not only the metadata)
    print(m.version("aiosmtpd"))
except Exception:
    pass
EOF
}

have="$(aiosmtpd_installed_version)"
if [ "$have" = "$AIOSMTPD_VERSION" ]; then
    log "aiosmtpd $have present"
else
    log "aiosmtpd present: '${have:-none}', want $AIOSMTPD_VERSION"
    "$PYTHON" -m pip install -q "aiosmtpd==$AIOSMTPD_VERSION"
    have="$(aiosmtpd_installed_version)"
    if [ "$have" != "$AIOSMTPD_VERSION" ]; then
        log "ERROR: aiosmtpd $AIOSMTPD_VERSION did not install (found '${have:-none}')"
        exit 1
    fi
    log "aiosmtpd $have installed"
fi

# ---------------------------------------------------------------- hat-drivers
# An abi3 manylinux wheel (CPython >= 3.10, x86_64) with its native serial module
# (hat/drivers/serial/_native_serial.abi3.so): nothing to compile. It pulls in its
# pure-Python dependencies (hat-aio, hat-json, pyserial, aiohttp, ...). The driver
# itself only as a wheel: its sdist would need a C toolchain and its build system.
hat_drivers_installed_version() {
    "$PYTHON" - <<'EOF' 2>/dev/null || true
import importlib.metadata as m
try:
    # the import itself must work, not only the metadata
    import hat.drivers.iec103, hat.drivers.iec60870.link, hat.drivers.serial  # noqa: F401
    print(m.version("hat-drivers"))
except Exception:
    pass
EOF
}

have="$(hat_drivers_installed_version)"
if [ "$have" = "$HAT_DRIVERS_VERSION" ]; then
    log "hat-drivers $have present"
else
    log "hat-drivers present: '${have:-none}', want $HAT_DRIVERS_VERSION"
    "$PYTHON" -m pip install -q --only-binary=hat-drivers "hat-drivers==$HAT_DRIVERS_VERSION"
    have="$(hat_drivers_installed_version)"
    if [ "$have" != "$HAT_DRIVERS_VERSION" ]; then
        log "ERROR: hat-drivers $HAT_DRIVERS_VERSION did not install (found '${have:-none}')"
        exit 1
    fi
    log "hat-drivers $have installed"
fi

# ---------------------------------------------------------------- pymodbus, python-snap7
# The independent Modbus (TCP and RTU) and S7 peers of the field I/O tests. pymodbus is
# pure Python, with pyserial for RTU over a pseudo-terminal; python-snap7 ships manylinux
# wheels carrying the Snap7 library itself (server and client): nothing to compile.
py_installed_version() { # DIST IMPORT...
    local dist="$1"; shift
    "$PYTHON" - "$dist" "$@" <<'EOF' 2>/dev/null || true
import importlib, importlib.metadata as m, sys
try:
    for module in sys.argv[2:]:
        importlib.import_module(module)  # the import itself must work, not only the metadata
    print(m.version(sys.argv[1]))
except Exception:
    pass
EOF
}

py_install() { # DIST VERSION IMPORT...
    local dist="$1" want="$2"; shift 2
    local have
    have="$(py_installed_version "$dist" "$@")"
    if [ "$have" = "$want" ]; then
        log "$dist $have present"
        return
    fi
    log "$dist present: '${have:-none}', want $want"
    "$PYTHON" -m pip install -q --only-binary=:all: "$dist==$want"
    have="$(py_installed_version "$dist" "$@")"
    if [ "$have" != "$want" ]; then
        log "ERROR: $dist $want did not install (found '${have:-none}')"
        exit 1
    fi
    log "$dist $have installed"
}

py_install pyserial "$PYSERIAL_VERSION" serial
py_install pymodbus "$PYMODBUS_VERSION" pymodbus.client pymodbus.server
py_install python-snap7 "$PYTHON_SNAP7_VERSION" snap7.client snap7.server

# ---------------------------------------------------------------- Sparkplug B peers
# Pure-Python wheels: paho-mqtt, tahu (the generated sparkplug_b_pb2) and the protobuf
# runtime tahu pins. The broker is Debian's mosquitto; the tests start their own
# instance on a free loopback port (the package's system service is not used).
py_install protobuf "$PROTOBUF_VERSION" google.protobuf
py_install paho-mqtt "$PAHO_MQTT_VERSION" paho.mqtt.client
py_install tahu "$TAHU_VERSION" tahu.sparkplug_b_pb2
if [ -x /usr/sbin/mosquitto ] || command -v mosquitto >/dev/null 2>&1; then
    log "mosquitto present"
else
    apt_install mosquitto
fi

# ---------------------------------------------------------------- postgresql
# Only the server binaries under /usr/lib/postgresql/*/bin are used. The package
# may create and start a system cluster on port 5432; that is harmless, the
# throwaway cluster of scripts/with-postgres.sh listens on its own free port and
# keeps its socket in its own temp dir.
if ls /usr/lib/postgresql/*/bin/initdb >/dev/null 2>&1; then
    log "postgresql present: $(ls -d /usr/lib/postgresql/*/bin | sort -V | tail -n1)"
else
    apt_install postgresql
    if ! ls /usr/lib/postgresql/*/bin/initdb >/dev/null 2>&1; then
        log "ERROR: postgresql installed but no initdb under /usr/lib/postgresql/*/bin"
        exit 1
    fi
    log "postgresql installed: $(ls -d /usr/lib/postgresql/*/bin | sort -V | tail -n1)"
fi

# ---------------------------------------------------------------- chromium
# The browser and its WebDriver come from the same Debian source package, so their
# versions always match. Headless only: no X server is needed.
apt_install chromium chromium-driver fonts-dejavu-core
if ! command -v chromedriver >/dev/null 2>&1; then
    log "ERROR: chromium-driver installed but no chromedriver on PATH"
    exit 1
fi
log "chromium: $(chromium --version 2>/dev/null | head -n1)"

# ---------------------------------------------------------------- iproute2
# `ip`: the network namespaces, bridges and veth pairs of scripts/netns-station.sh, in which
# crates/stanice/tests/netns.rs runs the Vsetín station one node per namespace (as root).
if command -v ip >/dev/null 2>&1; then
    log "iproute2 present"
else
    apt_install iproute2
fi

# ---------------------------------------------------------------- verify
# c104 2.2.1 has no c104.__version__ attribute (its .pyi claims one); the
# compiled module c104._c104 carries it.
log "verify: $("$PYTHON" -c 'import c104, c104._c104 as m; print("c104", m.__version__)')"
log "verify: aiosmtpd $("$PYTHON" -c 'import importlib.metadata as m, aiosmtpd.smtp; print(m.version("aiosmtpd"))')"
log "verify: hat-drivers $("$PYTHON" -c 'import importlib.metadata as m, hat.drivers.iec103, hat.drivers.serial; print(m.version("hat-drivers"))')"
log "verify: $(tshark --version 2>/dev/null | head -n1)"
log "verify: $("$PYTHON" -c 'import importlib.metadata as m, paho.mqtt.client, tahu.sparkplug_b_pb2; print("paho-mqtt", m.version("paho-mqtt"), "tahu", m.version("tahu"))')"
log "verify: mosquitto $(dpkg-query -W -f='${Version}' mosquitto 2>/dev/null || echo '(not from Debian)')"
log "verify: $("$(ls -d /usr/lib/postgresql/*/bin | sort -V | tail -n1)/initdb" --version)"
log "verify: $(chromedriver --version 2>/dev/null | head -n1)"
