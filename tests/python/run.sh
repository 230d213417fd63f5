#!/usr/bin/env bash
# The Python module's tests (tests/python/test_fractalbake.py) with pytest, against the build's
# library and program: run.sh FRACTALBAKE LIBFRACTALBAKE.so SOURCE_DIR. Not run (77) where no
# python3 has numpy and pytest (Debian: python3-numpy, python3-pytest), or where the library is
# built with the sanitizers (a Python interpreter cannot load it without their runtime first).
set -u
fb=$1 lib=$2 src=$3
if ldd "$lib" 2>/dev/null | grep -q libasan; then
  echo "SKIP: the library is built with AddressSanitizer"
  exit 77
fi
py=
for p in /usr/bin/python3 python3; do
  if "$p" -c "import numpy, pytest" 2>/dev/null; then py=$p; break; fi
done
if [ -z "$py" ]; then
  echo "SKIP: no python3 with numpy and pytest (apt-get install python3-numpy python3-pytest)"
  exit 77
fi
export FRACTALBAKE_LIBRARY=$lib FRACTALBAKE_PROGRAM=$fb PYTHONPATH=$src/python${PYTHONPATH:+:$PYTHONPATH}
exec "$py" -m pytest -q -p no:cacheprovider "$src/tests/python/test_fractalbake.py"
