# Sourced by test.sh: makes sure Open Image Denoise 2.x is there for the
# denoising tests, and exports PATHSTREAM_OIDN naming its folder. Debian 12
# does not package OIDN; PyPI's `pyoidn` wheel carries its shared libraries
# (and TBB), so a machine without it gets them from there, into target/oidn
# (the CPU and CUDA devices only: the SYCL and HIP ones are left out).
# Needs node-env.sh sourced first (ensure_python_venv).

oidn_dir="$PWD/target/oidn/lib"

ensure_oidn() {
    if [ -n "${PATHSTREAM_OIDN:-}" ] && [ -e "$PATHSTREAM_OIDN" ]; then
        return
    fi
    if [ -f "$oidn_dir/libOpenImageDenoise.so.2" ]; then
        export PATHSTREAM_OIDN="$oidn_dir"
        return
    fi
    if ldconfig -p 2>/dev/null | grep -q 'libOpenImageDenoise\.so\.2'; then
        return
    fi
    echo "oidn-env.sh: no Open Image Denoise here: fetching PyPI's pyoidn wheel into target/oidn" >&2
    ensure_python_venv
    local env="$PWD/target/oidn/venv" wheels="$PWD/target/oidn/wheel"
    rm -rf "$env" "$wheels" "$oidn_dir"
    python3 -m venv "$env"
    "$env/bin/pip" download -q --disable-pip-version-check --no-deps \
        "pyoidn==2.5.1.0" -d "$wheels"
    mkdir -p "$oidn_dir"
    python3 - "$wheels" "$oidn_dir" <<'PY'
import glob, os, re, sys, zipfile
wheel = glob.glob(os.path.join(sys.argv[1], "pyoidn-*.whl"))[0]
keep = re.compile(r"pyoidn/oidn/lib/(libOpenImageDenoise\.so\.2|libOpenImageDenoise_(core|device_cpu|device_cuda)\.so\.[0-9.]+|libtbb\.so\.12)$")
with zipfile.ZipFile(wheel) as z:
    for name in z.namelist():
        if keep.match(name):
            with open(os.path.join(sys.argv[2], os.path.basename(name)), "wb") as out:
                out.write(z.read(name))
PY
    rm -rf "$env" "$wheels"
    if [ ! -f "$oidn_dir/libOpenImageDenoise.so.2" ]; then
        echo "oidn-env.sh: the wheel held no libOpenImageDenoise.so.2" >&2
        return 1
    fi
    export PATHSTREAM_OIDN="$oidn_dir"
}
