"""Saving and loading sandwich models as plain JSON.

`save_model` writes a `SandwichSystem` to a small, human-readable JSON
file and `load_model` reads it back. The round trip is exact: floats are
written with Python's shortest round-tripping ``repr``, so the loaded
model has bitwise the same coefficients, the same `SandwichSystem.theta`
and the same simulated output as the saved one. (L1 and L2 are stored as
the coefficients of eq. (2.1), so they are loaded with monic
denominators; if the saved transfer functions were not monic, the loaded
ones are the same systems scaled to monic form, whose simulated output
agrees to rounding.)

File format (version 1)
-----------------------
One JSON object with these keys (the coefficients are those of
eqs. (2.1)-(2.2), as `SandwichSystem.coefficients` returns them)::

    {
      "format": "sandwichctl.SandwichSystem",
      "version": 1,
      "name": "paper",
      "dt": 1,
      "inputs": "u",
      "outputs": "y",
      "a": [0.1, 0.2],
      "b": [1.5],
      "q1": 1,
      "c": [1.2, 0.32],
      "d": [2.0, -0.1],
      "q2": 1,
      "m1": 1.0,
      "m2": 1.2,
      "D1": 0.5,
      "D2": 0.6,
      "metadata": {}
    }

``format``
    Always ``"sandwichctl.SandwichSystem"``.
``version``
    Format version, an integer; this is version 1.
``name``
    System name, or null for python-control's generic ``sys[i]`` names
    (the loaded model then gets a fresh generic name).
``dt``
    Sampling time: a positive number, or ``true`` for a discrete system
    with unspecified sampling time.
``inputs``, ``outputs``
    Names of the input and output signals (optional on reading; default
    ``"u"`` and ``"y"``).
``a``, ``b``, ``q1``
    L1 of eq. (2.1): ``a`` = [a1, ..., a_na] (may be empty), ``b`` =
    [b0, ..., b_nb] with b0 != 0, and the delay ``q1`` in samples. The
    lengths of the lists are the model's (declared) orders: trailing
    zeros are kept, so a model declared with na = 3 whose a3 is 0 is
    loaded with na = 3.
``c``, ``d``, ``q2``
    L2 of eq. (2.1), likewise.
``m1``, ``m2``, ``D1``, ``D2``
    Backlash slopes and thresholds of eq. (2.2).
``metadata``
    Free-form JSON object (where the data came from, the identifier
    settings, the date, ...); sandwichctl does not interpret it.

Readers reject other ``format`` values, versions they do not know,
files with missing keys or with values of the wrong type (each error
names the file and the key), orders above 1000, and files larger than
16 MiB; unknown extra keys are ignored.
"""

import json
import math
import numbers
import os
import re

import numpy as np
from scipy.optimize import OptimizeResult

from ..model.sandwich import SandwichSystem
from .._checks import MAX_ORDER, check_bool

#: Largest file `load_model` reads: a model is a few hundred bytes, plus
#: its metadata.
_MAX_BYTES = 16 * 2 ** 20
#: Deepest nesting of metadata save_model writes: json reads back less
#: than Python's recursion limit (a file of 990 levels was not loaded)
_MOST_DEPTH = 100

__all__ = ['save_model', 'load_model', 'FORMAT_VERSION']

#: Version of the JSON model format written by `save_model`.
FORMAT_VERSION = 1

_FORMAT_TAG = 'sandwichctl.SandwichSystem'
_REQUIRED = ('version', 'name', 'dt', 'a', 'b', 'q1', 'c', 'd', 'q2',
             'm1', 'm2', 'D1', 'D2')


def save_model(model, path, metadata=None):
    """Save a `SandwichSystem` to a JSON file (format in `sandwichctl.tools.io`).

    Parameters
    ----------
    model : SandwichSystem or IdentificationResult
        The model to save. Its coefficients and backlash parameters
        are saved. Given the result of `identify`, its model is saved
        and its summary goes into the metadata under 'identification':
        'method', 'success', 'message', 'fit', 'linear_fit' and 'offsets'
        (the operating point its model is about: 'u' and 'y', one value
        per experiment, or None where the fit had none), so that a loaded
        model is not taken out of its context.
    path : str, os.PathLike or file object
        Where to write; an open text file is written to and left open.
    metadata : dict, optional
        Free-form information stored with the model. It must be
        JSON-serialisable; numpy scalars and arrays are stored as numbers
        and lists.

    Raises
    ------
    TypeError
        If `model` is not a `SandwichSystem` or `metadata` is not a dict
        of JSON-serialisable values with string keys.
    ValueError
        If `metadata` contains NaN or infinity (not valid JSON), itself,
        or an int too large for a float, or nests more than 100 levels
        deep (load_model would not read it back); or if `path` holds a
        null byte or is a closed file.

    See Also
    --------
    load_model : the inverse.

    Examples
    --------
    >>> import os, tempfile
    >>> import sandwichctl as sw
    >>> plant = sw.examples.paper_plant()
    >>> path = os.path.join(tempfile.mkdtemp(), 'plant.json')
    >>> sw.save_model(plant, path, metadata={'source': 'Section 5'})
    >>> loaded = sw.load_model(path)
    >>> bool((loaded.theta == plant.theta).all())
    True

    A result keeps its verdict and offsets with the model:

    >>> u = sw.examples.paper_input(2000, seed=0)
    >>> res = sw.identify(u, plant.simulate(u).outputs + 2.0,
    ...                   **plant.orders, offsets='estimate')
    >>> sw.save_model(res, path)
    >>> meta = sw.load_model(path, return_metadata=True)[1]
    >>> meta['identification']['success']
    True
    >>> round(meta['identification']['offsets']['y'][0], 3)
    2.0
    """
    _check_path(path, 'write')
    data = _to_dict(model, metadata)
    try:
        text = _dumps(data)
    except ValueError as exc:
        raise ValueError(f"metadata must not contain NaN or infinity, which "
                         f"JSON cannot represent ({exc}); store them as "
                         f"strings or None") from None
    if hasattr(path, 'write'):
        try:
            path.write(text + '\n')
        except TypeError:                       # a binary file object
            raise TypeError(f"path must be a file name or a file opened "
                            f"in text mode ('w'); {_describe(path)} takes "
                            f"bytes") from None
        except OSError as exc:                  # one opened for reading
            raise _file_error(exc, _describe(path), 'write') from None
        return
    try:
        with open(os.fspath(path), 'w', encoding='utf-8') as f:
            f.write(text + '\n')
    except OSError as exc:
        raise _file_error(exc, _describe(path), 'write') from None


def load_model(path, return_metadata=False):
    """Load a `SandwichSystem` saved by `save_model`.

    Parameters
    ----------
    path : str, os.PathLike or file object
        File to read; an open text file is read from.
    return_metadata : bool, optional
        Also return the stored metadata dict.

    Returns
    -------
    model : SandwichSystem
        The model, with bitwise the same coefficients as the saved one.
    metadata : dict
        Only if `return_metadata` is True.

    Raises
    ------
    ValueError
        If the file is not JSON, is not a sandwichctl model, has a format
        version this sandwichctl cannot read, misses keys, or holds
        invalid coefficients.

    See Also
    --------
    save_model : the inverse; the format is described in `sandwichctl.tools.io`.

    Examples
    --------
    >>> import io
    >>> import sandwichctl as sw
    >>> buffer = io.StringIO()
    >>> sw.save_model(sw.examples.paper_plant(), buffer)
    >>> model, meta = sw.load_model(io.StringIO(buffer.getvalue()),
    ...                             return_metadata=True)
    >>> model.orders, meta
    ({'na': 2, 'nb': 0, 'nc': 2, 'nd': 1, 'q1': 1, 'q2': 1}, {})
    """
    _check_path(path, 'read')
    return_metadata = check_bool('return_metadata', return_metadata)
    where = _describe(path)
    try:
        if hasattr(path, 'read'):
            text = path.read(_MAX_BYTES + 1)
        else:
            with open(os.fspath(path), 'rb') as f:
                text = f.read(_MAX_BYTES + 1)
    except OSError as exc:
        raise _file_error(exc, where, 'read') from None
    if len(text) > _MAX_BYTES:
        raise ValueError(f"{where} is larger than {_MAX_BYTES // 2 ** 20} "
                         f"MiB: not a sandwichctl model file")
    if isinstance(text, bytes):
        try:
            text = text.decode('utf-8')
        except UnicodeDecodeError:
            raise ValueError(
                f"{where} is not a sandwichctl model file: it is binary, not "
                f"UTF-8 JSON text (a .npy or .npz array? load those with "
                f"numpy)") from None
    try:
        data = json.loads(text)
    except (ValueError, RecursionError) as exc:   # JSONDecodeError too
        raise ValueError(f"{where} is not valid JSON for a model "
                         f"({_short(str(exc))}); expected a model written "
                         f"by sandwichctl.save_model") from None
    model, metadata = _from_dict(data, where)
    return (model, metadata) if return_metadata else model


def _to_dict(model, metadata):

    result = None
    # an identification result (an OptimizeResult); a controller or a
    # compensator holds its model too, and is no model to save
    if isinstance(model, OptimizeResult) and \
            isinstance(model.get('model'), SandwichSystem):
        result, model = model, model.model
    if not isinstance(model, SandwichSystem):
        raise TypeError(f"model must be a sandwichctl.SandwichSystem (or "
                        f"the result of sw.identify); got "
                        f"{type(model).__name__}" + (
                            " (save its .model, the plant it was designed "
                            "on, or pickle it)" if isinstance(getattr(
                                model, 'model', None), SandwichSystem)
                            else ""))
    if metadata is None:
        metadata = {}
    if not isinstance(metadata, dict):
        raise TypeError(f"metadata must be a dict; got "
                        f"{type(metadata).__name__}")
    _check_metadata(metadata, 'metadata', set())
    if result is not None:
        if 'identification' in metadata:
            raise ValueError("metadata must not have the key "
                             "'identification' when saving a result: "
                             "save_model writes the result's summary there")
        metadata = {**metadata, 'identification': _summary(result)}
    co = model.coefficients
    name = model.name
    if name is None or re.match(r'^sys\[\d*\]$', name):
        name = None
    return {
        'format': _FORMAT_TAG,
        'version': FORMAT_VERSION,
        'name': name,
        'dt': _dt_to_json(model.dt),
        'inputs': model.input_labels[0],
        'outputs': model.output_labels[0],
        'a': [float(v) for v in co['a']],
        'b': [float(v) for v in co['b']],
        'q1': int(co['q1']),
        'c': [float(v) for v in co['c']],
        'd': [float(v) for v in co['d']],
        'q2': int(co['q2']),
        'm1': float(co['m1']),
        'm2': float(co['m2']),
        'D1': float(co['D1']),
        'D2': float(co['D2']),
        'metadata': metadata,
    }


def _summary(result):
    """What a result adds to the model's metadata: its verdict, fits and
    the offsets its model is about (the operating point a controller
    designed from the loaded model needs)."""
    def number(v):
        try:
            v = float(v)
        except (TypeError, ValueError):
            return None
        return v if math.isfinite(v) else None
    linear = getattr(result, 'linear', None)
    offsets = getattr(result, 'offsets', None)
    return {
        'method': str(getattr(result, 'method', '')),
        'success': bool(getattr(result, 'success', False)),
        'message': str(getattr(result, 'message', '')),
        'fit': number(getattr(result, 'fit', None)),
        'linear_fit': number(linear.get('fit')) if isinstance(linear, dict)
        else None,
        'offsets': None if not isinstance(offsets, dict) else {
            'method': str(offsets.get('method')),
            'u': [number(v) for v in np.atleast_1d(offsets.get('u', []))],
            'y': [number(v) for v in np.atleast_1d(offsets.get('y', []))]},
    }


def _from_dict(data, where):

    if not isinstance(data, dict) or data.get('format') != _FORMAT_TAG:
        found = (data.get('format') if isinstance(data, dict)
                 else type(data).__name__)
        raise ValueError(
            f"{where} is not a sandwichctl model file: expected \"format\": "
            f"\"{_FORMAT_TAG}\", got {found!r}")
    version = data.get('version', FORMAT_VERSION)   # missing: see below
    if isinstance(version, bool) or version != FORMAT_VERSION:
        raise ValueError(
            f"{where} has model format version {version!r}, but this "
            f"sandwichctl reads version {FORMAT_VERSION}; "
            + ("upgrade sandwichctl to read it" if isinstance(
                version, int) and version > FORMAT_VERSION
               else "the file is damaged or not from sandwichctl"))
    missing = [key for key in _REQUIRED if key not in data]
    if missing:
        raise ValueError(f"{where} is missing the key(s) {missing}; a "
                         f"version-1 model file needs {list(_REQUIRED)}")
    metadata = data.get('metadata', {})
    if not isinstance(metadata, dict):
        raise ValueError(f"{where}: 'metadata' must be a JSON object; got "
                         f"{type(metadata).__name__}")
    fields = {key: _coefficient_list(where, key, data[key], key in 'bd')
              for key in ('a', 'b', 'c', 'd')}
    for key in ('q1', 'q2'):
        fields[key] = _integer(where, key, data[key])
    for key in ('m1', 'm2', 'D1', 'D2'):
        fields[key] = _number(where, key, data[key])
    dt = data['dt']
    if not (dt is True or (isinstance(dt, numbers.Real)
                           and not isinstance(dt, bool)
                           and _finite_float(dt) and dt > 0)):
        raise ValueError(f"{where}: 'dt' must be a positive number or true;"
                         f" got {_short(dt)}")
    for key, default in (('name', None), ('inputs', 'u'), ('outputs', 'y')):
        value = data.get(key, default)
        if not (isinstance(value, str) and value) and not (
                key == 'name' and value is None):
            raise ValueError(
                f"{where}: {key!r} must be a non-empty string"
                + (" or null" if key == 'name' else "")
                + f"; got {value!r}")
        fields[key] = value
    try:
        model = SandwichSystem.from_coefficients(dt=dt, **fields)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where} holds an invalid model: {exc}") from None
    return model, metadata


def _coefficient_list(where, key, value, leading):
    """A list of finite numbers (at most MAX_ORDER + 1 of them)."""
    if not isinstance(value, list):
        raise ValueError(f"{where}: {key!r} must be a list of numbers; got "
                         f"{type(value).__name__} {_short(value)}")
    if len(value) > MAX_ORDER + 1:
        raise ValueError(f"{where}: {key!r} has {len(value)} coefficients; "
                         f"orders above {MAX_ORDER} are not accepted")
    if leading and not value:
        raise ValueError(f"{where}: {key!r} must hold at least {key}0")
    for i, item in enumerate(value):
        _number(where, f"{key}[{i}]", item)
    return [float(v) for v in value]


def _number(where, key, value):
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"{where}: {key!r} must be a number; got "
                         f"{type(value).__name__} {_short(value)}")
    if not _finite_float(value):
        raise ValueError(f"{where}: {key!r} must be a finite float; got "
                         f"{_short(value)}")
    return float(value)


def _finite_float(value):
    """Whether a real number is a finite float (an int of 400 digits is
    not: float() overflows)."""
    try:
        return math.isfinite(float(value))
    except OverflowError:
        return False


def _integer(where, key, value):
    if isinstance(value, bool) or not isinstance(value, int):
        raise ValueError(f"{where}: {key!r} must be an integer; got "
                         f"{type(value).__name__} {_short(value)}")
    if not 0 <= value <= MAX_ORDER:
        raise ValueError(f"{where}: {key!r} must be between 0 and "
                         f"{MAX_ORDER}; got {value}")
    return value


def _short(value):
    try:
        text = repr(value)
    except ValueError:          # an int of more digits than Python prints
        return f"an int of {value.bit_length()} bits"
    return text if len(text) <= 60 else text[:57] + '...'


def _check_path(path, mode):
    if not (isinstance(path, (str, os.PathLike)) or hasattr(path, mode)):
        raise TypeError(f"path must be a file name (str or os.PathLike) or "
                        f"an open text file; got {type(path).__name__} "
                        f"{_short(path)}")
    name = os.fspath(path) if isinstance(path, (str, os.PathLike)) else None
    if name == '':
        raise ValueError("path is empty; pass the name of a .json file")
    if isinstance(name, str) and '\0' in name:
        raise ValueError(f"path holds a null byte, which no file name "
                         f"can; got {_short(name)}")
    if getattr(path, 'closed', False) is True:
        raise ValueError(f"path is a closed file, {_describe(path)}; "
                         f"open it again")


def _file_error(exc, where, action):
    """`exc` again, of the same OSError subclass (so that ``except
    FileNotFoundError`` works), with a message that says what to do."""
    if isinstance(exc, IsADirectoryError):
        what = 'written by sw.save_model' if action == 'read' else 'to write'
        message = (f"path is a directory, not a model file: {where}; pass "
                   f"the name of a .json file {what}")
    elif isinstance(exc, FileNotFoundError) and action == 'read':
        message = (f"path names no file: {where} does not exist; check the "
                   f"name and the working directory ({os.getcwd()})")
    elif isinstance(exc, FileNotFoundError) and not os.path.isdir(
            os.path.dirname(os.fspath(exc.filename or '')) or '.'):
        message = (f"path is in a folder that does not exist: {where}; "
                   f"create the folder first (os.makedirs)")
    else:
        message = (f"cannot {action} the model file {where} (path): "
                   f"{exc.strerror or exc}")
    return (type(exc)(message) if exc.errno is None
            else type(exc)(exc.errno, message))


def _dumps(data):
    """JSON text with one top-level key per line and the lists inline."""
    lines = []
    for key, value in data.items():
        text = json.dumps(value, indent=2 if key == 'metadata' else None,
                          allow_nan=False, default=_json_default)
        text = text.replace('\n', '\n  ')      # nest metadata's lines
        lines.append(f"  {json.dumps(key)}: {text}")
    return '{\n' + ',\n'.join(lines) + '\n}'


def _dt_to_json(dt):
    if dt is True:
        return True
    if isinstance(dt, numbers.Integral):
        return int(dt)
    return float(dt)


def _check_metadata(value, where, seen):
    """What JSON would not give back as it was given is refused, naming
    the place: keys that are no strings (JSON turns 1 into '1'), a
    container holding itself, and ints beyond a float (or than Python
    prints); NaN and infinity are left to json (allow_nan=False)."""
    if isinstance(value, (dict, list, tuple)):
        if id(value) in seen:
            raise ValueError(f"{where} holds itself (a circular reference); "
                             f"JSON cannot store it")
        if len(seen) == _MOST_DEPTH:           # seen: the enclosing ones
            raise ValueError(f"metadata is nested more than {_MOST_DEPTH} "
                             f"levels deep, which load_model could not "
                             f"read back; flatten it")
        seen = seen | {id(value)}
        items = (value.items() if isinstance(value, dict)
                 else enumerate(value))
        for key, item in items:
            if isinstance(value, dict) and not isinstance(key, str):
                raise TypeError(f"{where} keys must be strings (JSON stores "
                                f"every key as one); got {key!r}")
            _check_metadata(item, f"{where}[{key!r}]", seen)
    elif isinstance(value, int) and not isinstance(value, bool) \
            and not _finite_float(value):
        raise ValueError(f"{where} is an int too large for a float; store "
                         f"it as a string")


def _json_default(obj):
    """Let json write numpy scalars and arrays in metadata."""
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    raise TypeError(f"metadata values must be JSON-serialisable (numbers, "
                    f"strings, lists, dicts); got {type(obj).__name__}")


def _describe(path):
    if hasattr(path, 'read'):
        name = getattr(path, 'name', type(path).__name__)
        return f"the file object {name!r}"
    return f"{os.fspath(path)!r}"
