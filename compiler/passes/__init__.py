"""Compiler passes, one module per pass, named after it (see :mod:`compiler.passes.base`)."""

from compiler.passes.base import CompileContext, Pass, run_pipeline
from compiler.passes.verify import Verify

__all__ = ["CompileContext", "Pass", "Verify", "run_pipeline"]
