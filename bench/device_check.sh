#!/usr/bin/env bash
# Runs bench/device_check.py on a GPU machine. Wheels carried in .wheels/ (pip download of the
# project's dependencies and gsplat) are installed first when prefect or gsplat is missing.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-python3}
if ! "$PY" -c "import prefect, gsplat" 2>/dev/null; then
    if [ -d .wheels ]; then
        "$PY" -m pip install --no-index --find-links .wheels -e . gsplat
    else
        echo "device_check.sh: prefect or gsplat missing and no .wheels/ folder carried" >&2
        exit 2
    fi
fi
export PYTHONPATH="$PWD" PYTHONUNBUFFERED=1 PREFECT_SERVER_ANALYTICS_ENABLED=false
out="${OUT:-bench/results}/device_check.json"
"$PY" bench/device_check.py --out "$out" "$@"
