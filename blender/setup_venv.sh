#!/usr/bin/env bash
# Idempotent setup of the Blender-as-a-Python-module virtualenv used by blender/render_*.py.
#
#   blender/setup_venv.sh            # creates <repo>/.venv-blender and installs bpy (pinned)
#   VENV=/some/where blender/setup_venv.sh
#
# bpy 5.0.1 ships wheels for CPython 3.11 only. The wheel is ~400 MB to download, ~1 GB installed.
# Skips every step that is already done (an existing venv whose `import bpy` works is left alone).
set -euo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/.." && pwd)"
VENV="${VENV:-$ROOT/.venv-blender}"
REQ="$HERE/requirements.txt"

log() { printf '[setup_venv] %s\n' "$*" >&2; }

# 1. Debian shared libraries bpy links against (it is a full Blender build, even headless).
DEB_LIBS="libx11-6 libxrender1 libxfixes3 libxi6 libxkbcommon0 libsm6 libice6 libxext6 libxcb1 libgl1 libxt6"
if command -v dpkg-query >/dev/null 2>&1; then
    missing=""
    for p in $DEB_LIBS; do
        if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
            missing="$missing $p"
        fi
    done
    if [ -n "$missing" ]; then
        if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then
            log "installing missing system libraries:$missing"
            DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends $missing \
                || { log "apt-get install failed; trying apt-get update first";
                     apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends $missing; }
        else
            log "missing system libraries:$missing"
            log "install them with:  sudo apt-get install -y$missing"
            log "(continuing; 'import bpy' will fail until they are installed)"
        fi
    else
        log "system libraries present"
    fi
else
    log "not a Debian system: make sure the equivalents of these are installed: $DEB_LIBS"
fi

# 2. Python 3.11.
PY=""
for cand in python3.11 python3; do
    if command -v "$cand" >/dev/null 2>&1 && \
       "$cand" -c 'import sys; sys.exit(0 if sys.version_info[:2] == (3, 11) else 1)' 2>/dev/null; then
        PY="$(command -v "$cand")"; break
    fi
done

# 3. Virtualenv (reuse if it already exists and is 3.11).
if [ -x "$VENV/bin/python" ] && \
   "$VENV/bin/python" -c 'import sys; sys.exit(0 if sys.version_info[:2] == (3, 11) else 1)' 2>/dev/null; then
    log "virtualenv exists: $VENV"
else
    if [ -z "$PY" ]; then
        log "ERROR: bpy==5.0.1 needs exactly Python 3.11, and neither python3.11 nor python3 is 3.11."
        log "Install it, e.g.  apt-get install python3.11 python3.11-venv   or   pyenv install 3.11"
        exit 1
    fi
    if [ -e "$VENV" ]; then
        log "ERROR: $VENV exists but is not a Python 3.11 virtualenv; remove it and re-run"
        exit 1
    fi
    log "creating virtualenv $VENV with $PY ($("$PY" --version 2>&1))"
    "$PY" -m venv "$VENV" || {
        log "ERROR: '$PY -m venv' failed; on Debian/Ubuntu install python3.11-venv"; exit 1; }
fi

# 4. bpy (pinned).
want="$(sed -n 's/^bpy==\([0-9.]*\).*/\1/p' "$REQ")"
have="$("$VENV/bin/python" -c 'import importlib.metadata as m; print(m.version("bpy"))' 2>/dev/null || true)"
if [ "$have" = "$want" ] && "$VENV/bin/python" -c 'import bpy' >/dev/null 2>&1; then
    log "bpy $have already installed and importable"
else
    log "installing $(grep -v '^#' "$REQ" | tr '\n' ' ')(~400 MB download, ~1 GB installed)"
    "$VENV/bin/python" -m pip install --disable-pip-version-check -r "$REQ"
    if ! "$VENV/bin/python" -c 'import bpy' >/dev/null 2>&1; then
        log "ERROR: bpy installed but 'import bpy' fails:"
        "$VENV/bin/python" -c 'import bpy' || true
        log "usually a missing system library (see the list above): ldd on the .so in bpy/ shows which"
        exit 1
    fi
fi
log "ok: $("$VENV/bin/python" -c 'import bpy; print("bpy", bpy.app.version_string)' 2>/dev/null | tail -n 1)"
log "run e.g.:  $VENV/bin/python $HERE/render_shadow.py -- --glb FILE.glb --out MASK.png"
