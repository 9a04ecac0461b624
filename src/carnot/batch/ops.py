"""One source, two compilers: how the batch formulas are written and specialized.

Every batch formula (:mod:`~carnot.batch.rigid`, :mod:`~carnot.batch.contact_space`,
:mod:`~carnot.batch.laws`, :mod:`~carnot.batch.coulomb`, :mod:`~carnot.batch.pipeline`) is a
module-level function marked :func:`formula`, written once as plain arithmetic on the numbers
of ONE impact (``+ - * /``, ``**``, comparisons, ``&``/``|`` on booleans, tuples for vectors)
plus three module globals: ``select(c, a, b)`` (``a`` where ``c`` else ``b``), ``sqrt`` and
``as_float`` (a boolean or integer as a float). As imported, they are NumPy's, so every
formula runs on NumPy arrays as it stands (the doctests do that). (A formula with adaptive
loops also tests ``carnot.batch.coulomb.any_true(mask)``: any row still running, or, compiled,
the one row's own flag, so that the loop ends per row.) :func:`specialize` rebinds them, and
the formulas' names, for a backend:

* an array-API namespace ``xp`` (NumPy, JAX, Dask, array_api_strict): every argument is an
  array of impacts, ``select`` is ``xp.where``: masks, no branches;
* :class:`PYTHON_FLOATS`: every argument is one Python float, nothing compiled: one impact
  costs about twenty microseconds of interpreted arithmetic, less than the dozens of small
  NumPy calls a general solver makes (:mod:`carnot.single`, the API's path for one point
  contact, runs the pipeline so);
* ``"numba"``: every argument is one float and every formula is compiled by Numba
  (``njit(cache=True)``); :mod:`carnot.batch.compiled` calls the pipeline per impact inside a
  ``prange`` loop, fused, so that no temporary array is ever written to memory.

So the compiled kernels and the array kernels are the same code, and the tests hold them to
each other as well as to :func:`carnot.solve_impact`.

Why module-level functions rebound by name, not closures: Numba's on-disk cache keys a
function by its code and its closure cells, and a closure cell holding a compiled function
pickles differently in every process, so closures would be compiled anew in every process
(seconds each). Rebinding globals keeps the code, and so the cache, stable. Two things the
cache does not see are put into the compiled functions' names instead: the contact law of
the pipeline (``impact__stick__...``: the one global that differs between builds of the same
code) and a digest of the source of every formula module (Numba checks only the file of the
function it loads, so a change in a callee's module would otherwise load stale code).

>>> import numpy as np
>>> select(np.array([True, False]), 1.0, -1.0).tolist(), float(sqrt(4.0))
([1.0, -1.0], 2.0)
"""

from __future__ import annotations

import functools
import hashlib
import importlib
import math
import types
from collections.abc import Callable
from typing import Any

import numpy as np

select: Callable[[Any, Any, Any], Any] = np.where
sqrt: Callable[[Any], Any] = np.sqrt


def as_float(x: Any) -> Any:
    """A boolean or integer as a number (identity for arrays: the caller casts)."""
    return x


class PYTHON_FLOATS:  # noqa: N801 - a backend namespace, named like the constants it stands beside
    """The backend of plain Python floats: ``where`` picks a branch (both are already
    evaluated, as everywhere), ``sqrt`` is :func:`math.sqrt`. A division by zero raises
    :class:`ZeroDivisionError` here where arrays give ``inf``: callers fall back to a general
    route then."""

    @staticmethod
    def where(c: Any, a: Any, b: Any) -> Any:
        return a if c else b

    sqrt = staticmethod(math.sqrt)


#: The modules that hold the formulas every law needs (a law's own module is added).
FORMULA_MODULES = ("carnot.batch.rigid", "carnot.batch.contact_space", "carnot.batch.laws",
                   "carnot.batch.pipeline")  # fmt: skip
#: Contact laws by name: (module, function). All share the signature of carnot.batch.laws.
LAWS: dict[str, tuple[str, str]] = {
    "frictionless": ("carnot.batch.laws", "frictionless"),
    "stick": ("carnot.batch.laws", "stick"),
    # Coulomb friction with slip, one law per restitution hypothesis (carnot.batch.coulomb)
    "coulomb_newton": ("carnot.batch.coulomb", "coulomb_newton"),
    "coulomb_poisson": ("carnot.batch.coulomb", "coulomb_poisson"),
    "coulomb_stronge": ("carnot.batch.coulomb", "coulomb_stronge"),
}
#: The formulas whose behaviour depends on the law (they get a name per law).
LAW_DEPENDENT = ("impact",)


def formula(fn: Callable[..., Any]) -> Callable[..., Any]:
    """Mark ``fn`` as a batch formula (see the module docstring for the rules)."""
    fn.__carnot_formula__ = True  # type: ignore[attr-defined]
    return fn


#: The compiled formulas' name tags by ``inline`` mode (:func:`specialize`): the two inlined
#: builds are different code, so their cache entries must not mix.
_INLINE_TAGS: dict[bool | str, str] = {False: "", True: "__inline", "ir": "__inline_ir"}


@functools.cache
def _numba_select() -> Any:
    """``select`` for Numba, as one LLVM ``select`` instruction: no branch, so nothing for
    the compiler to inline or to convert back into a ``select`` (the Coulomb law's 3D pass
    has hundreds of them: inlined as functions they took most of its minute of compile
    time), and vectorizable as it stands."""
    from numba.core import types as nbtypes
    from numba.core.errors import TypingError
    from numba.extending import intrinsic

    @intrinsic
    def select_ir(typingctx, c, a, b):  # type: ignore[no-untyped-def]
        a, b = nbtypes.unliteral(a), nbtypes.unliteral(b)
        out = typingctx.unify_types(a, b)
        if out is None or not isinstance(out, nbtypes.Number | nbtypes.Boolean):
            raise TypingError(f"select: no common number type for {a} and {b}")

        def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
            kinds = signature.args
            flag = context.cast(builder, args[0], kinds[0], nbtypes.boolean)
            return builder.select(flag, context.cast(builder, args[1], kinds[1], out),
                                  context.cast(builder, args[2], kinds[2], out))  # fmt: skip

        return out(c, a, b), codegen

    return select_ir


def _scalar_as_float(x: Any) -> float:
    return 1.0 * x  # float(bool) is not in Numba; arithmetic promotes


def _modules(law: str) -> list[types.ModuleType]:
    names = list(FORMULA_MODULES)
    if LAWS[law][0] not in names:
        names.insert(-1, LAWS[law][0])  # before the pipeline, which calls it
    return [importlib.import_module(name) for name in names]


#: The laws whose formulas are straight-line code (no adaptive loop): compiled with every
#: formula inlined, so that the compiler sees one loop body per impact and vectorizes it
#: across impacts (SIMD: see carnot.batch.compiled).
STRAIGHT_LINE_LAWS = ("frictionless", "stick")


@functools.cache
def specialize(backend: Any, law: str, inline: bool | str = False) -> types.SimpleNamespace:
    """Every formula rebound for ``backend`` (``"numba"`` or an array-API namespace), with the
    contact law ``law`` (a key of :data:`LAWS`) bound to the global name ``law``. With
    ``inline`` (Numba only) every formula is inlined into its caller by LLVM (Numba's
    ``forceinline``: LLVM's ``alwaysinline``): a straight-line law then compiles to one loop
    body that the compiler can vectorize. Each formula is still typed and lowered once per
    signature; Numba's own inlining (``inline="always"``) copies and types the callee's IR
    again at every call site, which took most of the Coulomb kernel's compile (56.6 s ->
    29.4 s for its three laws: docs/performance.md). ``inline="ir"`` asks for that copy
    all the same, where it measured faster: the 3D slip's start and end, whose loops over
    lanes LLVM vectorized less well from the inlined calls (3D cases 5-10 % slower).

    >>> ns = specialize(np, "frictionless")
    >>> [float(x) for x in ns.law((2.0, 0, 0, 7.0, 0, 7.0), (-1.0, 0.0, 0.0), 0.5, 0.0)[:2]]
    [0.75, 0.0]
    """
    if law not in LAWS:
        raise KeyError(law)
    if inline not in _INLINE_TAGS:
        raise ValueError(f"inline: one of False, True, 'ir', got {inline!r}")
    modules = _modules(law)
    namespace: dict[str, Any] = {}
    for module in modules:
        namespace.update({k: v for k, v in vars(module).items() if not k.startswith("__")})
    if backend == "numba":
        import numba

        def jit(fn: Any) -> Any:
            if inline == "ir":
                return numba.njit(cache=True, nogil=True, error_model="numpy",
                                  inline="always")(fn)  # fmt: skip
            return numba.njit(cache=True, nogil=True, error_model="numpy",
                              forceinline=bool(inline))(fn)  # fmt: skip

        namespace.update(select=_numba_select(), sqrt=math.sqrt,
                         as_float=jit(_scalar_as_float))  # fmt: skip
    else:
        namespace.update(select=backend.where, sqrt=backend.sqrt, as_float=as_float)

        def jit(fn: Any) -> Any:
            return fn

    digest = source_digest(modules)
    for module in modules:
        for name, fn in vars(module).items():
            if getattr(fn, "__carnot_formula__", False) and fn.__module__ == module.__name__:
                copy = types.FunctionType(fn.__code__, namespace, name, fn.__defaults__,
                                          fn.__closure__)  # fmt: skip
                copy.__module__ = fn.__module__
                copy.__doc__ = fn.__doc__
                tag = (f"__{law}" if name in LAW_DEPENDENT else "") + _INLINE_TAGS[inline]
                copy.__qualname__ = f"{name}{tag}__{digest}"
                namespace[name] = jit(copy)
    law_module, law_name = LAWS[law]
    namespace["law"] = namespace[law_name]
    return types.SimpleNamespace(**{k: v for k, v in namespace.items()
                                    if callable(v) or k == "law"})  # fmt: skip


def source_digest(modules: list[types.ModuleType]) -> str:
    """A short digest of the source files of ``modules`` (for the compiled functions'
    names: see the module docstring)."""
    digest = hashlib.sha256()
    for module in modules:
        with open(module.__file__ or "", "rb") as source:
            digest.update(source.read())
    return digest.hexdigest()[:12]


def stamped(fn: Callable[..., Any], digest: str,
            namespace: dict[str, Any] | None = None) -> Callable[..., Any]:  # fmt: skip
    """A copy of the function ``fn`` (the same code, globals, defaults and closure) whose
    qualified name ends in ``digest`` (the :func:`source_digest` of the modules whose rules
    it compiles), its globals ``namespace`` if given: what a compiled module decorates its
    functions with where they compile rules written in other modules.

    Numba stamps a function's cache entry with the source of the function's own file only,
    and a caller's entry holds the machine code of every callee it linked: a change in
    ``carnot.laws.cone`` would leave the multi-contact kernel loading the old cone from the
    cache. The name is part of the entry's file name, so a changed rule is a missing entry
    (compiled again), never a stale one.

    >>> import carnot.conventions as conventions
    >>> copy = stamped(conventions.as_vector, source_digest([conventions]))
    >>> copy.__qualname__.startswith("as_vector__"), copy([1, 2, 3]).tolist()
    (True, [1.0, 2.0, 3.0])
    """
    copy = types.FunctionType(fn.__code__, fn.__globals__ if namespace is None else namespace,
                              fn.__name__, fn.__defaults__, fn.__closure__)  # fmt: skip
    copy.__kwdefaults__ = fn.__kwdefaults__
    copy.__module__ = fn.__module__
    copy.__doc__ = fn.__doc__
    copy.__qualname__ = f"{fn.__qualname__}__{digest}"
    return copy


def compiled_rules(module: types.ModuleType, names: tuple[str, ...],
                   jit: Callable[[Callable[..., Any]], Any],
                   digest: str) -> dict[str, Any]:  # fmt: skip
    """The plain-Python rules ``names`` of ``module`` (functions of floats, such as
    :mod:`carnot.laws.cone`'s), each compiled by ``jit`` under a name stamped with
    ``digest`` (:func:`stamped`), the calls among them bound to the compiled copies (a
    compiled function can call only compiled ones; the module's own functions stay Python).
    ``names`` in the order they call each other, callees first.

    >>> import numba
    >>> from carnot.laws import cone
    >>> rules = compiled_rules(cone, ("project_onto_cone", "contact_law_residual"),
    ...                        numba.njit, source_digest([cone]))
    >>> # loaded, sliding at 1 m/s with no friction impulse (mu = 0.5): not the law
    >>> round(rules["contact_law_residual"](True, False, 0.5, 1.0, 1.0, 0.0, 0.0,
    ...                                     0.0, 0.0, 1.0), 6)
    0.447214
    """
    namespace = dict(vars(module))
    compiled: dict[str, Any] = {}
    for name in names:
        compiled[name] = namespace[name] = jit(stamped(getattr(module, name), digest, namespace))
    return compiled


def have_numba() -> bool:
    """Whether the compiled kernels are available (``numba`` importable)."""
    try:
        import numba  # noqa: F401
    except ImportError:  # pragma: no cover - numba is in the lock file
        return False
    return True
