"""llfsm's two small C parts, each standing in for Python code on a hot path and doing exactly
what it does: the recorder's tap (llfsm/bag/_tap.c) and turtlesim's stroke painter
(llfsm/sim/_paint.c).

Everything else is in pyproject.toml.  Both are optional: where no C compiler or Python headers
exist, the install goes on without them and the Python code runs instead, with the same bytes
and pixels, only slower (docs/recording.md, "What recording costs").  No contraction into fused
multiply-adds: the painter's floating-point operations must round as Python's do.
"""

from setuptools import Extension, setup

FLAGS = ["-O2", "-ffp-contract=off"]

setup(
    ext_modules=[
        Extension("llfsm.bag._tap", ["llfsm/bag/_tap.c"], optional=True, extra_compile_args=FLAGS),
        Extension("llfsm.sim._paint", ["llfsm/sim/_paint.c"], optional=True, extra_compile_args=FLAGS),
    ],
)
