"""Unpickling without running a pickle's code: the one kind of pickle snakesim reads, SB3's
``VecNormalize`` statistics (``vecnormalize.pkl``), through an allow-list of the classes and functions
such a file names, within bounds of time and memory.

``pickle.load`` calls whatever callable a pickle names, so a file from elsewhere could run any code on
load. Here every name a pickle looks up goes through :meth:`StatisticsUnpickler.find_class`, which
returns only the allowed ones and refuses the file otherwise, before anything it names is called.

Allowed callables can still be asked for too much: ``RunningMeanStd(1e-4, (300_000_000,))`` in an
83-byte file allocated 3 GB. So every call, construction and state the pickle makes goes through a
check of its arguments first (:class:`StatisticsUnpickler`, on Python's own unpickler, whose steps can
be checked one by one; the C one's memo table and ``BYTEARRAY8`` also allocate what a few bytes ask):

- statistics and spaces (``RunningMeanStd``, ``Box``) hold at most the model's observations (without
  a model, ``LIMITS['space_size']``); a ``VecNormalize`` is restored from its saved state, never built
  (that needs an env);
- numpy arrays hold together at most ``LIMITS['config_bytes']`` of data, as a saved file stores each
  array's bytes (checked from the shape and dtype before an array is made), of plain numeric dtypes;
- a pickle takes at most :data:`MAX_OPERATIONS` steps (empty sets of 1 byte each took 216 bytes).
"""

from __future__ import annotations

import functools
import importlib
import io
import math
import operator
import pickle
import reprlib
import struct
from typing import Any

import numpy as np

from snakesim.limits import LIMITS

# What a VecNormalize pickle holds: the wrapper and its running statistics, numpy arrays (rebuilt from
# their bytes; older pickles rebuild them with _reconstruct) and scalars, and the gymnasium spaces it
# keeps, with their random generators (numpy's own unpickling helpers, which call nothing else).
_ALLOWED: dict[str, frozenset[str]] = {
    "stable_baselines3.common.vec_env.vec_normalize": frozenset({"VecNormalize"}),
    "stable_baselines3.common.running_mean_std": frozenset({"RunningMeanStd"}),
    "gymnasium.spaces.box": frozenset({"Box"}),
    "numpy": frozenset({"ndarray", "dtype"}),
    "numpy._core.multiarray": frozenset({"_reconstruct", "scalar"}),
    "numpy._core.numeric": frozenset({"_frombuffer"}),
    "numpy.random._pickle": frozenset({"__generator_ctor", "__bit_generator_ctor"}),
    "numpy.random._pcg64": frozenset({"PCG64"}),
    "numpy.random.bit_generator": frozenset({"SeedSequence", "__pyx_unpickle_SeedSequence"}),
}
# numpy 1.x wrote numpy.core.*; numpy 2 has them as numpy._core.* (and importing numpy.core warns).
_RENAMED = {"numpy.core.multiarray": "numpy._core.multiarray", "numpy.core.numeric": "numpy._core.numeric"}

#: Most steps (opcodes) a statistics pickle may take: a VecNormalize of ``LIMITS['envs']`` envs with
#: randomized physics takes about 40,000; a million objects stay well under 1 GB.
MAX_OPERATIONS = 1_000_000
#: Most bytes of numpy data a statistics file's arrays hold together: a saved file stores every
#: array's bytes, so they fit in what the file may hold.
MAX_ARRAY_BYTES = LIMITS["config_bytes"]
#: numpy dtypes a statistics file holds: booleans and numbers (no objects, fields or sub-arrays).
_PLAIN_KINDS = "biufc"
# Python classes the pickle restores from their state (NEWOBJ with no arguments, then BUILD).
_RESTORED = ("VecNormalize", "RunningMeanStd", "Box")


class RefusedPickle(ValueError):
    """A pickle that names something a statistics file does not hold, or asks too much of what it
    may name; the message says which."""


_REPR = reprlib.Repr()
_REPR.maxlevel, _REPR.maxtuple, _REPR.maxlist, _REPR.maxdict = 2, 4, 4, 2
_REPR.maxstring = _REPR.maxother = _REPR.maxlong = 24
# Keys of dicts and members of sets: what a VecNormalize file keys by. Nothing deeper, which hashing
# would follow down (a tuple a million levels deep, hashed, overflowed the C stack: a 1 MB crash).
_KEYS = (str, int, float, bool, bytes, type(None))


def _excerpt(value: Any, limit: int = 24) -> str:
    """A short, one-line rendering of a value from the file (at most ``limit`` characters)."""
    text = _REPR.repr(value).encode("unicode_escape").decode("ascii")
    return text if len(text) <= limit else text[: limit - 3] + "..."


@functools.cache
def _objects() -> dict[tuple[str, str], Any]:
    """The allowed names' objects, imported once."""
    found = {}
    for module, names in _ALLOWED.items():
        imported = importlib.import_module(module)
        for name in names:
            found[(module, name)] = getattr(imported, name)
    return found


def _sizes(shape: Any, what: str) -> tuple[int, ...]:
    """A shape (an int or a tuple of ints >= 0) as a tuple; RefusedPickle otherwise."""
    items = (shape,) if isinstance(shape, (int, np.integer)) else shape
    if not isinstance(items, (tuple, list)) or len(items) > 32:
        raise RefusedPickle(f"the pickle gives {what} the shape {_excerpt(shape)}, which is not a shape")
    try:
        sizes = tuple(operator.index(n) for n in items)
    except TypeError:
        raise RefusedPickle(
            f"the pickle gives {what} the shape {_excerpt(shape)}, which is not a shape"
        ) from None
    if any(n < 0 for n in sizes):
        raise RefusedPickle(f"the pickle gives {what} the shape {_excerpt(shape)}, which is not a shape")
    return sizes


def _plain_dtype(value: Any, what: str) -> np.dtype:
    """``value`` as a numpy dtype of booleans or numbers; RefusedPickle for anything else (objects,
    fields, sub-arrays, strings, or a size that a few bytes of the file set)."""
    try:
        dtype = value if isinstance(value, np.dtype) else np.dtype(value)
    except (TypeError, ValueError):
        raise RefusedPickle(f"the pickle gives {what} the dtype {_excerpt(value)}") from None
    if (
        dtype.kind not in _PLAIN_KINDS
        or dtype.fields is not None
        or dtype.subdtype is not None
        or dtype.hasobject
        or not 0 < dtype.itemsize <= 16
    ):
        shown = _excerpt(str(dtype))
        raise RefusedPickle(
            f"the pickle gives {what} the dtype {shown}, which a VecNormalize file does not hold"
        )
    return dtype


def _counted(step: Any) -> Any:
    """An unpickler's step that first counts itself (:meth:`StatisticsUnpickler._count`)."""

    def counted(self: StatisticsUnpickler) -> None:
        self._count()
        step(self)

    return counted


class StatisticsUnpickler(pickle._Unpickler):  # noqa: SLF001 - Python's unpickler, whose steps we check
    """An unpickler that looks up only the names of :data:`_ALLOWED`, and checks what the pickle asks
    of them before it is done (see the module's docstring).

    ``observation_size``: the observations the model takes (the statistics' size); None: at most
    ``LIMITS['space_size']``.
    """

    def __init__(self, file: io.BytesIO, *, size: int, observation_size: int | None = None) -> None:
        super().__init__(file)
        self._size = size  # the file's length: nothing in it is longer
        self._operations = 0
        self._array_bytes = 0
        space = LIMITS["space_size"]
        if observation_size is None:
            self._elements, self._elements_what = space, f"{space:,} values (LIMITS['space_size'])"
        else:
            self._elements = min(int(observation_size), space)
            self._elements_what = f"the model's {self._elements} observations"
        objects = _objects()
        self._names = {id(obj): f"{module}.{name}" for (module, name), obj in objects.items()}
        self._by_name = {name: obj for (_, name), obj in objects.items()}
        # The check each allowed callable's arguments pass before it is called.
        checks = {
            "VecNormalize": self._check_vec_normalize,
            "RunningMeanStd": self._check_running_mean_std,
            "Box": self._check_box,
            "ndarray": self._check_ndarray,
            "dtype": self._check_dtype,
            "_reconstruct": self._check_reconstruct,
            "_frombuffer": self._check_frombuffer,
            "scalar": self._check_scalar,
            "__generator_ctor": self._check_generator_ctor,
            "__bit_generator_ctor": self._check_bit_generator_ctor,
            "PCG64": self._check_restored_only,
            "SeedSequence": self._check_restored_only,
            "__pyx_unpickle_SeedSequence": self._check_unpickle_seed_sequence,
        }
        self._checks = {id(obj): checks[name] for (_, name), obj in objects.items()}
        self._restored = tuple(self._by_name[name] for name in _RESTORED)
        # What BUILD may set the state of: instances of these (never a class or a function).
        self._buildable = (
            *self._restored,
            np.ndarray,
            np.dtype,
            np.random.Generator,
            np.random.BitGenerator,
            np.random.SeedSequence,
        )

    # -- names ------------------------------------------------------------------------------------
    def find_class(self, module: str, name: str) -> Any:
        module = _RENAMED.get(module, module)
        if name not in _ALLOWED.get(module, ()):
            raise RefusedPickle(f"the pickle names {module}.{name}, which a VecNormalize file does not hold")
        return _objects()[(module, name)]

    def persistent_load(self, pid: Any) -> Any:
        raise RefusedPickle("the pickle names a persistent object, which a VecNormalize file does not hold")

    # -- bounds -----------------------------------------------------------------------------------
    def _charge(self, nbytes: int, what: str) -> None:
        """Counts ``nbytes`` of array data against :data:`MAX_ARRAY_BYTES`, before it is allocated."""
        self._array_bytes += nbytes
        if self._array_bytes > MAX_ARRAY_BYTES:
            raise RefusedPickle(
                f"the pickle builds {what}: more array data than a statistics file holds "
                f"({MAX_ARRAY_BYTES >> 20} MiB, LIMITS['config_bytes'])"
            )

    def _array(self, shape: Any, dtype: Any, what: str) -> tuple[tuple[int, ...], np.dtype]:
        sizes, dtype = _sizes(shape, what), _plain_dtype(dtype, what)
        nbytes = math.prod(sizes) * dtype.itemsize
        self._charge(nbytes, f"{what} of shape {_excerpt(sizes)} ({nbytes:,} bytes)")
        return sizes, dtype

    def _statistics(self, shape: Any, what: str) -> int:
        """The values of statistics or a space of ``shape``: at most the model's observations."""
        sizes = _sizes(shape, what)
        count = math.prod(sizes)
        if count > self._elements:
            raise RefusedPickle(
                f"the pickle builds {what} of shape {_excerpt(sizes)}: more than {self._elements_what}"
            )
        return count

    # -- calls ------------------------------------------------------------------------------------
    def _call(self, func: Any, args: Any) -> Any:
        """``func(*args)`` for an allowed callable, once its arguments are checked."""
        name = self._names.get(id(func))
        if name is None:
            raise RefusedPickle(
                f"the pickle calls a {type(func).__name__}, which a VecNormalize file does not"
            )
        if type(args) is not tuple:
            raise pickle.UnpicklingError(f"the arguments of {name} are not a tuple")
        # Checked and named in messages by its own name (``RunningMeanStd``).
        self._checks[id(func)](name.rpartition(".")[2], *args)
        if func is np.dtype:
            # Always a fresh dtype (copy=True), never numpy's shared one, which a BUILD would change
            # for everyone; and one of numbers.
            return _plain_dtype(np.dtype(args[0], bool(args[1]) if len(args) > 1 else False, True), name)
        return func(*args)

    def _check_vec_normalize(self, name: str, *args: Any) -> None:
        raise RefusedPickle(
            f"the pickle builds {name} from arguments: a VecNormalize file restores a saved one"
        )

    def _check_restored_only(self, name: str, *args: Any) -> None:
        # numpy restores these from their state (through __bit_generator_ctor and
        # __pyx_unpickle_SeedSequence); called, a seed of megabytes took quadratic time.
        raise RefusedPickle(f"the pickle calls {name}, which a VecNormalize file restores from its state")

    def _check_running_mean_std(self, name: str, epsilon: Any = 1e-4, shape: Any = (), *rest: Any) -> None:
        count = self._statistics(shape, name)
        self._charge(2 * 8 * count, f"{name} of {count:,} values")

    def _check_box(self, name: str, low: Any = None, high: Any = None, shape: Any = None, *rest: Any) -> None:
        if shape is None:
            shape = max((np.shape(bound) for bound in (low, high)), key=math.prod)
        count = self._statistics(shape, name)
        self._charge(4 * 8 * count, f"{name} of {count:,} values")

    def _check_ndarray(self, name: str, shape: Any = (), dtype: Any = float, *rest: Any) -> None:
        if rest:
            raise RefusedPickle(f"the pickle builds {name} over a buffer, which a VecNormalize file does not")
        self._array(shape, dtype, name)

    def _check_dtype(self, name: str, spec: Any = None, align: Any = False, copy: Any = False) -> None:
        pass  # checked once made (making a dtype allocates nothing)

    def _check_reconstruct(self, name: str, subtype: Any = None, shape: Any = (), dtype: Any = None) -> None:
        if subtype is not np.ndarray:
            raise RefusedPickle(f"the pickle calls {name} for {_excerpt(subtype)}, not numpy.ndarray")
        self._array(shape, dtype, "a numpy array")

    def _check_frombuffer(self, name: str, buffer: Any = b"", dtype: Any = None, *rest: Any) -> None:
        if not isinstance(buffer, (bytes, bytearray, pickle.PickleBuffer)):
            raise RefusedPickle(f"the pickle calls {name} on {_excerpt(buffer)}, not bytes")
        _plain_dtype(dtype, "a numpy array")
        self._charge(memoryview(buffer).nbytes, "a numpy array")

    def _check_scalar(self, name: str, dtype: Any = None, *rest: Any) -> None:
        self._charge(_plain_dtype(dtype, "a numpy scalar").itemsize, "a numpy scalar")

    def _check_generator_ctor(self, name: str, bit_generator: Any = None, *ctor: Any) -> None:
        if ctor and ctor[0] is not self._by_name["__bit_generator_ctor"]:
            raise RefusedPickle(f"the pickle calls {name} with {_excerpt(ctor[0])}, not numpy's own")

    def _check_bit_generator_ctor(self, name: str, bit_generator: Any = "MT19937", *rest: Any) -> None:
        if not isinstance(bit_generator, str) and bit_generator is not self._by_name["PCG64"]:
            raise RefusedPickle(f"the pickle calls {name} for {_excerpt(bit_generator)}")

    def _check_unpickle_seed_sequence(self, name: str, kind: Any = None, *rest: Any) -> None:
        if kind is not np.random.SeedSequence:
            raise RefusedPickle(f"the pickle calls {name} for {_excerpt(kind)}")

    def _new(self, cls: Any, args: Any, kwargs: Any) -> Any:
        """``cls.__new__(cls)``: only the Python classes that are restored from their state, and
        with no arguments (which a saved object never has)."""
        if not any(cls is restored for restored in self._restored):
            name = self._names.get(id(cls), type(cls).__name__)
            raise RefusedPickle(
                f"the pickle makes {name} through __new__, which a VecNormalize file does not"
            )
        if args or kwargs:
            raise RefusedPickle(f"the pickle makes {self._names[id(cls)]} with arguments to __new__")
        return cls.__new__(cls)

    # -- the steps that call, construct or set state ---------------------------------------------------
    def load_reduce(self) -> None:
        args = self.stack.pop()
        self.stack[-1] = self._call(self.stack[-1], args)

    def load_newobj(self) -> None:
        args = self.stack.pop()
        cls = self.stack.pop()
        self.append(self._new(cls, args, {}))

    def load_newobj_ex(self) -> None:
        kwargs = self.stack.pop()
        args = self.stack.pop()
        cls = self.stack.pop()
        self.append(self._new(cls, args, kwargs))

    def _instantiate(self, klass: Any, args: list[Any]) -> None:  # INST and OBJ (protocols 0 and 1)
        if not args and any(klass is restored for restored in self._restored):
            self.append(self._new(klass, (), {}))
        else:
            self.append(self._call(klass, tuple(args)))

    def load_build(self) -> None:
        state, inst = self.stack[-1], self.stack[-2]
        if not isinstance(inst, self._buildable) or isinstance(inst, type):
            raise RefusedPickle(
                f"the pickle sets the state of {_excerpt(inst)}, which a VecNormalize file does not"
            )
        if isinstance(inst, np.dtype):
            self._check_dtype_state(state)
        elif isinstance(inst, np.ndarray):
            self._check_array_state(state)
        elif getattr(inst, "__setstate__", None) is None and not (
            isinstance(state, dict) and all(isinstance(k, str) and not k.startswith("__") for k in state)
        ):
            raise RefusedPickle(f"the pickle sets attributes of {type(inst).__name__} that it does not have")
        super().load_build()
        if isinstance(inst, np.dtype):
            _plain_dtype(inst, "numpy.dtype")

    def _check_dtype_state(self, state: Any) -> None:
        # numpy writes (3, byteorder, None, None, None, -1, -1, 0) for a dtype of numbers: no
        # sub-array, names, fields, size or flags of its own (which could make floats into objects).
        plain = (
            isinstance(state, tuple)
            and len(state) in (8, 9)
            and state[0] in (3, 4)
            and state[1] in ("<", ">", "|", "=")
            and state[2:5] == (None, None, None)
            and state[5:8] == (-1, -1, 0)
            and (len(state) == 8 or state[8] is None)
        )
        if not plain:
            shown = _excerpt(state)
            raise RefusedPickle(
                f"the pickle gives a numpy dtype the state {shown}, which a dtype of numbers lacks"
            )

    def _check_array_state(self, state: Any) -> None:
        # (version, shape, dtype, is_fortran, data), the data the array's bytes.
        if not isinstance(state, tuple) or len(state) not in (4, 5):
            raise RefusedPickle(f"the pickle gives a numpy array the state {_excerpt(state)}")
        shape, dtype, _, data = state[-4:]
        if not isinstance(data, (bytes, bytearray)):
            raise RefusedPickle(f"the pickle gives a numpy array the data {_excerpt(data)}, not bytes")
        self._array(shape, dtype, "a numpy array")

    def _check_keys(self, keys: Any, what: str) -> None:
        for key in keys:
            if type(key) not in _KEYS:
                raise RefusedPickle(f"the pickle {what} {_excerpt(key)}, which a VecNormalize file does not")

    def load_setitem(self) -> None:
        if type(self.stack[-3]) is not dict:
            raise RefusedPickle(f"the pickle sets an item of {_excerpt(self.stack[-3])}, not of a dict")
        self._check_keys(self.stack[-2:-1], "keys a dict by")
        super().load_setitem()

    def load_setitems(self) -> None:
        items = self.stack
        if type(self.metastack[-1][-1] if self.metastack and self.metastack[-1] else None) is not dict:
            raise RefusedPickle("the pickle sets items of something that is not a dict")
        self._check_keys(items[0::2], "keys a dict by")
        super().load_setitems()

    def load_dict(self) -> None:
        self._check_keys(self.stack[0::2], "keys a dict by")
        super().load_dict()

    def load_additems(self) -> None:
        if type(self.metastack[-1][-1] if self.metastack and self.metastack[-1] else None) is not set:
            raise RefusedPickle("the pickle adds items to something that is not a set")
        self._check_keys(self.stack, "puts in a set")
        super().load_additems()

    def load_frozenset(self) -> None:
        self._check_keys(self.stack, "puts in a set")
        super().load_frozenset()

    def load_bytearray8(self) -> None:
        # Python's own allocates the length the file states, before reading it.
        (length,) = struct.unpack("<Q", self.read(8))
        if length > self._size:
            raise pickle.UnpicklingError(f"a bytearray of {length:,} bytes in a file of {self._size:,}")
        data = self.read(length)
        if len(data) != length:
            raise pickle.UnpicklingError("pickle data was truncated")
        self.append(bytearray(data))

    def _count(self) -> None:
        self._operations += 1
        if self._operations > MAX_OPERATIONS:
            raise RefusedPickle(
                f"the pickle takes more than {MAX_OPERATIONS:,} steps, which a VecNormalize file does not"
            )

    # Every step counted; the steps that call, construct, set state or size a buffer checked.
    dispatch = dict(pickle._Unpickler.dispatch)  # noqa: SLF001
    dispatch[pickle.REDUCE[0]] = load_reduce
    dispatch[pickle.NEWOBJ[0]] = load_newobj
    dispatch[pickle.NEWOBJ_EX[0]] = load_newobj_ex
    dispatch[pickle.BUILD[0]] = load_build
    dispatch[pickle.BYTEARRAY8[0]] = load_bytearray8
    dispatch[pickle.SETITEM[0]] = load_setitem
    dispatch[pickle.SETITEMS[0]] = load_setitems
    dispatch[pickle.DICT[0]] = load_dict
    dispatch[pickle.ADDITEMS[0]] = load_additems
    dispatch[pickle.FROZENSET[0]] = load_frozenset
    dispatch = {code: _counted(step) for code, step in dispatch.items()}


def load_statistics(data: bytes, observation_size: int | None = None) -> Any:
    """The object pickled in ``data``, built from allowed names only and within bounds (RefusedPickle
    otherwise; the errors of a malformed pickle pass through). ``observation_size``: the model's, which
    the statistics must not exceed."""
    return StatisticsUnpickler(io.BytesIO(data), size=len(data), observation_size=observation_size).load()
