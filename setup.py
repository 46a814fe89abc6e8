"""llfsm's two small C parts, each standing in for Python code on a hot path and doing exactly
what it does: the recorder's tap (llfsm/bag/_tap.c) and turtlesim's stroke painter
(llfsm/sim/_paint.c).

Everything else is in pyproject.toml.  Both are optional: where no C compiler or Python headers
exist, the install goes on without them and the Python code runs instead, with the same bytes
and pixels, only slower (docs/recording.md, "What recording costs").  `LLFSM_NO_C=1` in the
environment makes a built install run without them too (their imports fail; the tests that
need them are skipped).  No contraction into fused multiply-adds: the painter's
floating-point operations must round as Python's do.

What they need:

- CPython's full C API, not the limited API (no `Py_LIMITED_API`).  The tap is fast because it
  reads a message's slots at the offsets of their member descriptors, checked with the class's
  type version tag and `_PyType_Lookup` so that it reads exactly what Python's attribute access
  would: none of that is in the limited API, and through the limited API it would get each
  attribute with `PyObject_GetAttr`, which is what the generated Python function already does.
  The stable ABI would let one wheel serve several Python versions, but these are built from
  source at install, for the interpreter that installs them, and never shipped as wheels.
- CPython with the GIL.  Both rely on it: the tap appends to its spool and reads slots while no
  other thread can change them, and the painter writes into a bytearray another thread could
  resize.  On a free-threaded build (`Py_GIL_DISABLED`) they are not built (each C file also
  refuses to compile there), and the Python code runs.  Other interpreters (PyPy) skip them too.
"""

import platform
import sys
import sysconfig

from setuptools import Extension, setup

FLAGS = ["-O2", "-ffp-contract=off"]

ext_modules = [
    Extension("llfsm.bag._tap", ["llfsm/bag/_tap.c"], optional=True, extra_compile_args=FLAGS),
    Extension("llfsm.sim._paint", ["llfsm/sim/_paint.c"], optional=True, extra_compile_args=FLAGS),
]
if sysconfig.get_config_var("Py_GIL_DISABLED"):
    print("llfsm: free-threaded CPython: the C parts are not built (they need the GIL)", file=sys.stderr)
    ext_modules = []
elif platform.python_implementation() != "CPython":
    print("llfsm: not CPython: the C parts are not built (they use CPython's own C API)", file=sys.stderr)
    ext_modules = []

setup(ext_modules=ext_modules)
