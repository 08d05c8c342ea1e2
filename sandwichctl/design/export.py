r"""Export a servo controller or a compensator as dependency-free C.

`export_c` writes ``name.h`` and ``name.c``: plain C99 that includes only
``<math.h>``, ``<stddef.h>`` and ``<string.h>``, allocates nothing and
keeps no global state (the whole memory is one struct, ``name_state``),
for a microcontroller, a DSP, drive firmware or a real-time task::

    size_t name_state_size(void);          /* sizeof(name_state), for FFI */
    void   name_reset(name_state *s);
    double name_step(name_state *s, double r_ahead, double y);

(``name_step(s, v_d)`` for a `SandwichCompensator`; ``float`` throughout
with ``dtype='float'``.) The coefficients are ``static const`` at full
precision, and the step does the operations of the compiled Python step
(`ServoController.step`, `SandwichCompensator.simulate`) in the same
order, so that in double precision the C controller returns the same u,
bit for bit where the compiler keeps that order (``-std=c99`` does: it
contracts no multiply-add). The backlash inverse's discrete decisions
(rise, fall or hold; smoothed or exact) are therefore the same too.

Layout of the generated step
----------------------------
A `ServoController` is written from its packed parameters (see the
compiled kernel, ``_servo_kernel``): the feedback block on the error
``r(k) - y(k)``, the pre-inverse block ``r_ahead -> w``, the delay line
of w, the backlash inverse with its rate-limited band offset, the
post-inverse block (its output scaled by the band's gain, estimated
online by recursive least squares when the controller adapts), and the
linear feedforward. A block with no states
is a gain, written inline; a delay line of length 0 is left out. Its
operating point (u0, y0) sits in the state, so that
``name_reset_at(s, y, u)`` starts a running axis bumplessly like
``ctrl.reset(y=y, u=u)``. A `SandwichCompensator` is its backlash
inverse followed by the L1-inverse block.
"""

import os
import re
import textwrap
from importlib import metadata
from pathlib import Path

import numpy as np

from .compensator import SandwichCompensator
from .servo import ServoController
from ._export_adapt import blend_body, guard_parts
from ._export_blocks import Block as _Block
from ._servo_kernel import IX, NSCALAR, SCALARS
from ..model.sandwich import SandwichSystem

__all__ = ['export_c']

#: C type, literal suffix, abs function and printf format of each dtype:
#: %.17g and %.9g are the fewest digits that give back every double and
#: every float exactly
_TYPES = {'double': ('double', '', 'fabs', '%.17g'),
          'float': ('float', 'f', 'fabsf', '%.9g')}

_C_KEYWORDS = frozenset(
    'auto break case char const continue default do double else enum '
    'extern float for goto if inline int long register restrict return '
    'short signed sizeof static struct switch typedef union unsigned void '
    'volatile while _Bool _Complex _Imaginary'.split())


#: the standard headers of C99 and C11: a file <name>.h beside the user's
#: code would shadow them (gcc searches -I folders first, even for <...>)
_C_HEADERS = frozenset(
    'assert complex ctype errno fenv float inttypes iso646 limits locale '
    'math setjmp signal stdalign stdarg stdatomic stdbool stddef stdint '
    'stdio stdlib stdnoreturn string tgmath threads time uchar wchar '
    'wctype'.split())

#: longest name: file names stop at 255 bytes on most file systems
MOST_NAME = 200


def _check_name(name):
    if not isinstance(name, str):
        raise TypeError(f"name must be a string (a C identifier); got "
                        f"{type(name).__name__} {name!r}")
    if (not re.fullmatch(r'[A-Za-z][A-Za-z0-9_]*', name)
            or name in _C_KEYWORDS):
        raise ValueError(
            f"name must be a C identifier that is no C keyword: a letter, "
            f"then letters, digits or '_' (it prefixes every function, "
            f"e.g. 'servo' gives servo_step); got {name!r}")
    if len(name) > MOST_NAME:
        raise ValueError(f"name must be at most {MOST_NAME} characters (it "
                         f"names the files {name[:8]}....h and .c); got "
                         f"{len(name)}")
    if name.lower() in _C_HEADERS:    # a file system may ignore case
        raise ValueError(f"name {name!r} would write {name}.h, which "
                         f"shadows the standard header <{name.lower()}.h>; "
                         f"choose another name")
    return name


def _check_directory(directory):
    if not isinstance(directory, (str, os.PathLike)):
        raise TypeError(f"directory must be a path (str or pathlib.Path); "
                        f"got {type(directory).__name__} {directory!r}")
    path = Path(directory).expanduser()     # "~/fw" as a shell reads it
    try:
        if path.exists() and not path.is_dir():
            raise ValueError(f"directory {str(path)!r} is a file, not a "
                             f"folder")
        path.mkdir(parents=True, exist_ok=True)
    except (OSError, ValueError) as exc:   # a null byte, a name too long
        if str(exc).startswith('directory '):
            raise
        raise ValueError(f"directory {str(path)!r} cannot be created: "
                         f"{exc}") from None
    if not os.access(path, os.W_OK | os.X_OK):
        raise ValueError(f"directory {str(path)!r} is not writable; choose "
                         f"a folder you can write to")
    return path


def _comment(text):
    """`text` made safe inside a C block comment: ASCII, no comment
    delimiters, no trigraphs."""
    text = text.encode('ascii', 'backslashreplace').decode('ascii')
    text = text.replace('*/', '* /').replace('/*', '/ *')
    while '??' in text:
        text = text.replace('??', '? ?')
    return text


def _wrap(lines, width=74):
    """Comment lines, safe (see `_comment`) and wrapped to `width`; the
    continuation of an indented line is indented two more."""
    out = []
    for line in lines:
        line = _comment(line)
        lead = len(line) - len(line.lstrip())
        indent = ' ' * (lead + 2 if lead else 0)
        out += textwrap.wrap(line, width, subsequent_indent=indent,
                             break_long_words=False,
                             break_on_hyphens=False) or ['']
    return out


def _numbers(values):
    return '[' + ', '.join(f"{v:.17g}" for v in np.ravel(values)) + ']'


def _model_text(model):
    """Lines that identify the model: its repr and its coefficients at
    full precision."""
    if isinstance(model, SandwichSystem):
        co = model.coefficients
        lines = str(model).splitlines()
        lines.append('coefficients: ' + ', '.join(
            f"{k} = {_numbers(v) if np.ndim(v) else f'{v:.17g}'}"
            for k, v in co.items()))
        return lines
    return [f"TransferFunction, dt = {model.dt!r}",
            f"  num = {_numbers(model.num[0][0])}",
            f"  den = {_numbers(model.den[0][0])}"]


class _Writer:
    """Text of the generated code for one name and dtype."""

    def __init__(self, name, dtype):
        self.name = name
        self.T, self.suffix, self.abs, self.fmt = _TYPES[dtype]

    def num(self, value):
        """A C literal of `value` in the dtype (exactly representable)."""
        if self.T == 'float':
            value = np.float32(value)
        text = self.fmt % value
        if not any(c in text for c in '.en'):
            text += '.0'
        return text + self.suffix

    def const(self, tag, value, note=''):
        note = f"    /* {note} */" if note else ''
        return (f"static const {self.T} {self.name}_{tag} = "
                f"{self.num(value)};{note}")

    def array(self, tag, values, per_line):
        """A static const array, `per_line` values a line (a matrix row)."""
        values = np.ravel(values)
        body = ',\n    '.join(
            ', '.join(self.num(v) for v in values[i:i + per_line])
            for i in range(0, values.size, per_line))
        return (f"static const {self.T} {self.name}_{tag}[{values.size}] = "
                f"{{\n    {body}\n}};")


def _block_function(w, nmax):
    T = w.T
    pad = ' ' * len(f"static {T} {w.name}_block(")
    return f"""\
/* One sample of a state-space block of n <= {nmax} states: return
   C x + D u, then x <- A x + B u (the order of the Python kernel). */
static {T} {w.name}_block(const {T} *A, const {T} *B, const {T} *C,
{pad}{T} D, size_t n, {T} *x, {T} u)
{{
    {T} out = D * u;
    {T} tmp[{nmax}];
    size_t i, j;
    for (i = 0; i < n; ++i)
        out += C[i] * x[i];
    for (i = 0; i < n; ++i) {{
        {T} acc = B[i] * u;
        for (j = 0; j < n; ++j)
            acc += A[i * n + j] * x[j];
        tmp[i] = acc;
    }}
    memcpy(x, tmp, n * sizeof *x);
    return out;
}}
"""


def _shift_function(w):
    T = w.T
    return f"""\
/* Push value into a delay line of n >= 1 samples; return the value pushed
   n samples ago. */
static {T} {w.name}_shift({T} *line, size_t n, {T} value)
{{
    {T} out = line[n - 1];
    memmove(line + 1, line, (n - 1) * sizeof *line);
    line[0] = value;
    return out;
}}
"""


def _inverse_functions(w, m1, m2, D1, D2, width):
    """The backlash of eq. (2.2) and its (smoothed) right inverse, as in
    `backlash_step` and `_inverse_step`."""
    T, n, f = w.T, w.name, w.num
    zero = f(0.0)
    consts = '\n'.join([
        w.const('m1', m1, 'slope of the increase line'),
        w.const('m2', m2, 'slope of the decrease line'),
        w.const('D1', D1, 'threshold of the increase line'),
        w.const('D2', D2, 'threshold of the decrease line')]
        + ([w.const('width', width, 'smoothing width (in v)')]
           if width > 0 else []))
    if width > 0:
        choose = f"""\
    if ({w.abs}(dv) < {n}_width) {{          /* smoothed: spread the jump */
        const {T} t = {w.abs}(dv) / {n}_width;
        const {T} edge = zone == 1 ? *v_prev / {n}_m1 + {n}_D1
                                   : *v_prev / {n}_m2 - {n}_D2;
        const {T} m = zone == 1 ? {n}_m1 : {n}_m2;
        x = *x_prev + t * t * ({f(3.0)} - {f(2.0)} * t) * (edge - *x_prev)
            + dv / m;
        exact = 0;
    }} else {{
        x = zone == 1 ? v_d / {n}_m1 + {n}_D1 : v_d / {n}_m2 - {n}_D2;
        exact = 1;
    }}"""
        declare, take = 'int zone, z, exact;', 'exact && z == zone'
    else:
        choose = (f"    x = zone == 1 ? v_d / {n}_m1 + {n}_D1 "
                  f": v_d / {n}_m2 - {n}_D2;")
        declare, take = 'int zone, z;', 'z == zone'
    return f"""\
/* The backlash model inverted (L1 -> backlash -> L2, eq. (2.2)). */
{consts}

/* Eq. (2.2), one step: the backlash output for input x after memory
   (x_prev, v_prev); *zone is 1 (increase), -1 (decrease) or 0 (memory). */
static {T} {n}_backlash({T} x, {T} x_prev, {T} v_prev, int *zone)
{{
    if (x > x_prev && x > v_prev / {n}_m1 + {n}_D1) {{
        *zone = 1;
        return {n}_m1 * (x - {n}_D1);
    }}
    if (x < x_prev && x < v_prev / {n}_m2 - {n}_D2) {{
        *zone = -1;
        return {n}_m2 * (x + {n}_D2);
    }}
    *zone = 0;
    return v_prev;
}}

/* The right inverse of the backlash: the input x(k) that gives the output
   v_d. The memory (*x_prev, *v_prev) = (x(k-1), v_hat(k-1)) becomes
   (x(k), v_hat(k)), v_hat being the output the inverse expects. */
static void {n}_inverse({T} v_d, {T} *x_prev, {T} *v_prev)
{{
    const {T} dv = v_d - *v_prev;
    {T} x, v_hat;
    {declare}
    if (dv == {zero})
        return;                               /* hold */
    zone = dv > {zero} ? 1 : -1;
{choose}
    if (zone * (x - *x_prev) <= {zero})
        return;                    /* unreachable by a monotone step: hold */
    v_hat = {n}_backlash(x, *x_prev, *v_prev, &z);
    if ({take})
        v_hat = v_d;        /* on the intended line: v_d itself, unrounded */
    *x_prev = x;
    *v_prev = v_hat;
}}
"""


def _servo_parts(ctrl, w):
    """(state members, constants, step body, extra prototypes, reset
    body) of a ServoController."""
    p = ctrl._p
    at = dict(zip(IX, (int(v) for v in ctrl._ix)))     # the layout by name
    preview, lead = at['preview'], at['lead']
    compensate = bool(at['compensate'])
    sc = dict(zip(SCALARS, p[at['off_scalar']:at['off_scalar'] + NSCALAR]))
    # name_reset restores the design's operating point, as reset() does
    sc['u0'], sc['y0'] = ctrl._design['operating_point']

    def block(tag, what, part):
        return _Block.packed(tag, what, p, at['off_' + part], at['n_' + part])

    fb = block('fb', 'feedback C(z), error r(k) - y(k) -> u_fb', 'fb')
    pre = block('pre', 'pre-inverse, r_ahead -> w (the backlash output '
                'wanted)', 'pre')
    post = block('post', 'post-inverse, x -> u_post', 'post')
    lin = block('lin', 'linear feedforward, r_ahead -> u_lin', 'lin')
    adapts, blends = bool(at['adapt']), bool(at['blend'])
    oth = block('oth', 'the other linear feedforward, r_ahead -> u_other '
                '(blended in online)', 'other')
    ps = block('ps', "process sensitivity P / (1 + C P), the band path's "
               "output -> the regressor of its gain", 'ps')
    if w.T == 'float':
        # a realization whose coefficients survive the rounding
        fb, pre, post, lin, oth, ps = (b.for_float() for b in
                                       (fb, pre, post, lin, oth, ps))
    T, n = w.T, w.name
    members = []
    if preview:
        members.append((f"{T} r_line[{preview}];",
                        'reference delay line (preview)'))
    if lead:
        members.append((f"{T} w_line[{lead}];", 'delay line of w (lead)'))
    for b in (fb, pre):
        if b.n:
            members.append((f"{T} {b.tag}[{b.n}];", f"{b.tag} block"))
    if compensate:
        members += [(f"{T} x_prev;", 'backlash inverse: x(k-1)'),
                    (f"{T} v_prev;", 'backlash inverse: v_hat(k-1)'),
                    (f"{T} offset;", 'band offset (rate limited)')]
    for b in (post, lin) + ((ps,) if adapts else ()):
        if b.n:
            members.append((f"{T} {b.tag}[{b.n}];", f"{b.tag} block"))
    if adapts:
        members += [(f"{T} band_dg;", "the band's gain g, less 1"),
                    (f"{T} band_q;", 'its covariance: 1 - cov / p0')]
    if blends:
        for tag, size, what in (('oth', oth.n, 'oth block'),
                                ('ps2', ps.n, 'ps block on u_other - u_lin')):
            if size:
                members.append((f"{T} {tag}[{size}];", what))
        members += [(f"{T} blend;", "the other feedforward's share b"),
                     (f"{T} blend_q;", "its variance: 1 - var / pb0"),
                     (f"{T} blend_c;", "its covariance with g, over pb0")]
    guard = (guard_parts(w, sc) if sc['hunt'] > 0 else ([], [], []))
    members += guard[0]
    members += [(f"{T} u0;", 'operating point: u at the model\'s zero'),
                (f"{T} y0;", 'operating point: y at the model\'s zero')]

    consts = ['/* Operating point (u0, y0) given at design. */',
              w.const('u0', sc['u0']), w.const('y0', sc['y0']), '']
    if not compensate:
        consts += ['/* A linear design: no backlash inverse. The pre and '
                   'post blocks and the', '   scalars of the inverse '
                   'path are zero gains, kept so that the step does what',
                   '   the compiled Python step does. */', '']
    for b in ((fb, pre, post, lin) + ((ps,) if adapts else ())
              + ((oth,) if blends else ())):
        consts += b.constants(w) + ['']
    consts += ['/* Feedforward scalars. */',
               w.const('mbar', sc['mbar'], 'mean backlash slope'),
               w.const('alpha', sc['alpha'], 'share of w fed to the post '
                       'block')]
    if compensate and sc['rate'] > 0:
        consts.append(w.const('rate', sc['rate'],
                              'largest change of the band offset a sample'))
    if adapts:
        consts += [
            "/* Online estimate of the band's gain (recursive least "
            "squares). */",
            w.const('lam', sc['lam'], 'forgetting factor'),
            w.const('p0', sc['p0'], 'initial covariance'),
            w.const('pmax', sc['pmax'], 'largest covariance'),
            w.const('gmax', sc['gmax'], 'largest gain')]
    if blends:
        consts += [w.const('pb0', sc['pb0'], "the blend's initial variance"),
                   w.const('pbmax', sc['pbmax'], 'its largest variance')]
    consts += guard[1]
    functions = []
    nmax = max(b.n for b in (fb, pre, post, lin, ps, oth))
    if nmax:
        functions.append(_block_function(w, nmax))
    if preview or lead:
        functions.append(_shift_function(w))
    if compensate:
        functions.append(_inverse_functions(
            w, sc['m1'], sc['m2'], sc['D1'], sc['D2'], sc['width']))

    r_now = (f"{n}_shift(s->r_line, {preview}, ra)" if preview else 'ra')

    def late(d):
        """r_ahead d samples ago (`_servo_kernel._late`)."""
        return ('ra' if d == 0 else 'r_now' if d == preview
                else f"s->r_line[{d}]")
    r_lin, r_oth = late(at['d_lin']), late(at['d_other'])
    w_now = f"{n}_shift(s->w_line, {lead}, w_ahead)" if lead else 'w_ahead'
    body = [f"    const {T} ra = r_ahead - s->y0;",
            f"    const {T} yd = y - s->y0;",
            f"    {T} r_now, e, u_fb, w_ahead, w, x, u_ff;",
            '    /* feedback on the error against the reference of this '
            'sample */',
            f"    r_now = {r_now};",
            '    e = r_now - yd;'] + guard[2] + [
            f"    u_fb = {fb.call(w, 'e')};",
            '    /* feedforward: the backlash output wanted, the inverse, '
            "L1's inverse */",
            f"    w_ahead = {pre.call(w, 'ra')};",
            f"    w = {w_now};",
            f"    x = {n}_alpha * w / {n}_mbar;"]
    if compensate:
        body += ['    {                       /* the band offset */',
                 f"        {T} target, step;",
                 f"        {n}_inverse(w_ahead, &s->x_prev, &s->v_prev);",
                 f"        target = s->x_prev - w_ahead / {n}_mbar;",
                 '        step = target - s->offset;']
        if sc['rate'] > 0:
            body += [f"        if (step > {n}_rate)",
                     f"            step = {n}_rate;",
                     f"        else if (step < -{n}_rate)",
                     f"            step = -{n}_rate;"]
        body += ['        s->offset += step;',
                 '        x += s->offset;',
                 '    }']
    body += [f"    u_ff = {post.call(w, 'x')};"]
    if blends:
        body += blend_body(w, ps, lin, oth, r_lin, r_oth)
    elif adapts:
        one, zero = w.num(1.0), w.num(0.0)
        body += ["    {                       /* the band's gain, online */",
                 f"        {T} phi, g, cov, gain;",
                 f"        phi = {ps.call(w, 'u_ff')};",
                 f"        g = {one} + s->band_dg;",
                 f"        cov = {n}_p0 * ({one} - s->band_q);",
                 f"        gain = cov * phi / ({n}_lam + phi * phi * cov);",
                 '        g += gain * (r_now - yd);',
                 f"        cov = (cov - gain * phi * cov) / {n}_lam;",
                 f"        if (cov > {n}_pmax)",
                 f"            cov = {n}_pmax;",
                 f"        if (g < {zero})",
                 f"            g = {zero};",
                 f"        else if (g > {n}_gmax)",
                 f"            g = {n}_gmax;",
                 f"        s->band_dg = g - {one};",
                 f"        s->band_q = {one} - cov / {n}_p0;",
                 '        u_ff *= g;',
                 '    }']
    if not blends:
        body += [f"    u_ff += {lin.call(w, r_lin)};"]
    body += ['    return s->u0 + u_fb + u_ff;']
    signature = f"{T} {n}_step({n}_state *s, {T} r_ahead, {T} y)"
    reset = [f"    s->u0 = {n}_u0;", f"    s->y0 = {n}_y0;"]
    return members, consts, functions, signature, body, reset


def _compensator_parts(comp, w):
    inv = comp.backlash_inverse
    A, B, C, D = comp.linear_matrices
    L1 = _Block('l1', "L1's inverse z^-q1 L1^-1, x_d -> u", A.shape[0],
                A, B, C, D)
    if w.T == 'float':
        L1 = L1.for_float()
    T, n = w.T, w.name
    members = [(f"{T} x_prev;", 'backlash inverse: x(k-1)'),
               (f"{T} v_prev;", 'backlash inverse: v_hat(k-1)')]
    if L1.n:
        members.append((f"{T} l1[{L1.n}];", "L1-inverse block"))
    consts = L1.constants(w)
    functions = ([_block_function(w, L1.n)] if L1.n else []) + [
        _inverse_functions(w, inv.m1, inv.m2, inv.D1, inv.D2,
                           inv.smoothing)]
    body = [f"    {n}_inverse(v_d, &s->x_prev, &s->v_prev);",
            f"    return {L1.call(w, 's->x_prev')};"]
    signature = f"{T} {n}_step({n}_state *s, {T} v_d)"
    return members, consts, functions, signature, body, []


def _version():
    try:
        return metadata.version('sandwichctl')
    except metadata.PackageNotFoundError:        # pragma: no cover
        return 'unknown'


def _dt_text(dt):
    return 'unspecified (dt=True)' if dt is True else f"{dt:.17g} s"


def _usage(obj, w):
    """The header's account of how to call the step, and of the object:
    paragraphs (wrapped later) and indented lines."""
    n = w.name
    if isinstance(obj, ServoController):
        u0, y0 = obj._design['operating_point']
        return [
            f"Use: one {n}_state per axis (static or on the stack), "
            f"{n}_reset(&s) once, then once per sample, every dt:",
            '',
            f"    u = {n}_step(&s, r_ahead, y);",
            '',
            f"  r_ahead  the reference {obj.preview} sample(s) ahead, "
            f"r(k + {n.upper()}_PREVIEW)",
            '  y        the measurement y(k) just read',
            '  u        the drive reference u(k) to apply now',
            '',
            f"Sample time: {_dt_text(obj.dt)}. Preview: {obj.preview} "
            f"sample(s). Arithmetic: {w.T}.",
            '',
            f"Operating point: u0 = {u0:.17g}, y0 = {y0:.17g}. r, y and u "
            f"are in raw units, and (u0, y0) is the model's zero. "
            f"{n}_reset_at(&s, y, u) takes the measured y and the u "
            f"applied now as the operating point instead: a bumpless start "
            f"on a running axis, like ctrl.reset(y=y, u=u).",
            '',
            'Controller (its repr, with the notes of its design):',
            *('  ' + line for line in repr(obj).splitlines()),
            '',
            'Designed from the model:',
            *('  ' + line for line in _model_text(obj.model))]
    return [
        f"Use: {n}_reset(&s) once, then once per sample, every dt:",
        '',
        f"    u = {n}_step(&s, v_d);",
        '',
        '  v_d  the backlash output wanted (from a linear controller '
        "designed for the compensator's design plant z^-q1 L2)",
        '  u    the plant input u(k) to apply now',
        '',
        f"Sample time: {_dt_text(obj.dt)}. Delay: q1 = {obj.delay} "
        f"sample(s): v(k) = v_d(k - q1) for an exact model. Arithmetic: "
        f"{w.T}.",
        '',
        'Compensator:',
        *('  ' + line for line in str(obj).splitlines()),
        '',
        'Inverting the model:',
        *('  ' + line for line in _model_text(obj.model))]


def _header(obj, w, members, signature):
    n, guard = w.name, w.name.upper()
    kind = ('servo controller' if isinstance(obj, ServoController)
            else 'sandwich compensator')
    doc = [f"{n}.h: a {kind} in plain C99.",
           f"Generated by sandwichctl {_version()} (sandwichctl.export_c); "
           f"do not edit, export again.", ''] + _usage(obj, w)
    width = max(len(m) for m, _ in members)
    struct = '\n'.join(f"    {m.ljust(width)}  /* {c} */"
                       for m, c in members)
    macros = []
    if obj.dt is not True:
        macros.append(f"#define {guard}_DT {obj.dt:.17g}    "
                      f"/* sample time, s */")
    if isinstance(obj, ServoController):
        macros.append(f"#define {guard}_PREVIEW {obj.preview}    "
                      f"/* samples of reference preview */")
        extra = (f"/* Reset with the operating point (u0, y0) = (u, y): "
                 f"a bumpless start. */\n"
                 f"void {n}_reset_at({n}_state *s, {w.T} y, {w.T} u);\n")
    else:
        macros.append(f"#define {guard}_DELAY {obj.delay}    "
                      f"/* q1: v(k) = v_d(k - q1) */")
        extra = ''
    comment = '\n'.join((' * ' + line).rstrip() for line in _wrap(doc))
    return f"""\
/*
{comment}
 */
#ifndef {guard}_H
#define {guard}_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {{
#endif

{chr(10).join(macros)}

/* The whole memory of the controller: one per axis. */
typedef struct {n}_state {{
{struct}
}} {n}_state;

/* sizeof({n}_state), for callers through a foreign-function interface. */
size_t {n}_state_size(void);

/* Back to rest: every internal state zero, the operating point as
   exported. */
void {n}_reset({n}_state *s);
{extra}
/* One sample; see above. */
{signature};

#ifdef __cplusplus
}}
#endif

#endif /* {guard}_H */
"""


def _source(obj, w, consts, functions, signature, body, reset):
    n = w.name
    reset_at = ''
    if isinstance(obj, ServoController):
        reset_at = f"""
void {n}_reset_at({n}_state *s, {w.T} y, {w.T} u)
{{
    {n}_reset(s);
    s->u0 = u;
    s->y0 = y;
}}
"""
    return f"""\
/* {n}.c: generated by sandwichctl {_version()} (sandwichctl.export_c); see
   {n}.h. The step does the operations of the Python step in the same
   order. Do not edit: export again. */
#include <math.h>
#include <string.h>

#include "{n}.h"

{chr(10).join(consts).strip()}

{chr(10).join(functions)}
size_t {n}_state_size(void)
{{
    return sizeof({n}_state);
}}

void {n}_reset({n}_state *s)
{{
    memset(s, 0, sizeof *s);
{chr(10).join(reset)}
}}
{reset_at}
{signature}
{{
{chr(10).join(body)}
}}
"""


def export_c(obj, directory, name='servo', dtype='double'):
    r"""Write a controller or a compensator as dependency-free C.

    Writes ``<name>.h`` and ``<name>.c`` to `directory`: plain C99 that
    includes only ``<math.h>``, ``<stddef.h>`` and ``<string.h>``, with no
    dynamic allocation and no global state (the memory is the struct
    ``<name>_state``). The step mirrors the compiled Python step operation
    for operation, so in double precision it returns the same u (see the
    module notes). The header documents the sample time, the preview, the
    operating point, the model the object was designed from, its notes
    and the package version; its functions are::

        size_t name_state_size(void);     /* sizeof(name_state) */
        void   name_reset(name_state *s);
        double name_step(name_state *s, double r_ahead, double y);
        void   name_reset_at(name_state *s, double y, double u);

    For a `SandwichCompensator` the step is ``name_step(s, v_d)`` and
    there is no ``name_reset_at``. With ``dtype='float'`` every
    ``double`` is a ``float``.

    Parameters
    ----------
    obj : ServoController or SandwichCompensator
        What to export (``sw.servo_controller(...)`` or
        ``sw.sandwich_compensator(...)``). A controller's ``name_reset``
        restores the operating point of its design, as ``ctrl.reset()``
        does; one taken by ``ctrl.reset(y=..., u=...)`` is set on the
        target by ``name_reset_at``.
    directory : str or pathlib.Path
        Folder for the two files (created if missing; files of the same
        name are overwritten).
    name : str, optional
        C identifier prefixing the files, the state type and every
        function (default 'servo').
    dtype : {'double', 'float'}, optional
        Arithmetic of the generated code (default 'double'); 'float' is
        for microcontrollers without a double-precision FPU, with the
        coefficients rounded to float and each linear block in the
        realization whose float response strays least from double
        (docs/deploy.md).

    Returns
    -------
    header, source : pathlib.Path
        The paths of ``<name>.h`` and ``<name>.c``.

    Raises
    ------
    TypeError
        If `obj` is not a `ServoController` or a `SandwichCompensator`, or
        `directory` or `name` has the wrong type.
    ValueError
        If `name` is no C identifier, `dtype` is not 'double' or 'float',
        `directory` is a file or cannot be written, or a coefficient is
        not finite (or too large for a float).

    See Also
    --------
    servo_controller, sandwich_compensator

    Notes
    -----
    Compile with, e.g., ``gcc -std=c99 -Wall -Wextra -Werror -pedantic
    -O2 -c servo.c``. Keep ``-std=c99`` (or ``-ffp-contract=off``): a
    compiler that fuses a multiply and an add into one FMA instruction
    rounds once instead of twice, and the result drifts from Python's by
    a few ulps. ``docs/deploy.md`` has a main loop, the mapping of raw
    sensor counts and the measured cost and float error.

    Examples
    --------
    >>> import tempfile, sandwichctl as sw
    >>> ctrl = sw.servo_controller(sw.examples.paper_plant())
    >>> folder = tempfile.mkdtemp()
    >>> header, source = sw.export_c(ctrl, folder, name='axis')
    >>> header.name, source.name
    ('axis.h', 'axis.c')
    >>> 'float axis_step(axis_state *s, float' in header.read_text()
    False
    >>> 'double axis_step(axis_state *s, double r_ahead, double y);' in \
    ...     header.read_text()
    True
    """
    if not isinstance(obj, (ServoController, SandwichCompensator)):
        raise TypeError(
            f"obj must be a ServoController (sw.servo_controller) or a "
            f"SandwichCompensator (sw.sandwich_compensator); got "
            f"{type(obj).__name__}")
    name = _check_name(name)
    if not isinstance(dtype, str) or dtype not in _TYPES:
        raise ValueError(f"dtype must be 'double' or 'float'; got "
                         f"{dtype!r}")
    if isinstance(obj, ServoController):
        values = obj._p
    else:
        inv = obj.backlash_inverse
        values = np.concatenate([np.ravel(M) for M in obj.linear_matrices]
                                + [[inv.m1, inv.m2, inv.D1, inv.D2,
                                    inv.smoothing]])
    if not np.all(np.isfinite(values)):
        raise ValueError("obj has coefficients that are not finite; it "
                         "cannot be exported")
    if dtype == 'float' and np.any(np.abs(values)
                                   > np.finfo(np.float32).max):
        raise ValueError("obj has coefficients beyond the range of a float "
                         "(3.4e38); export with dtype='double'")
    folder = _check_directory(directory)
    w = _Writer(name, dtype)
    parts = (_servo_parts if isinstance(obj, ServoController)
             else _compensator_parts)(obj, w)
    members, consts, functions, signature, body, reset = parts
    header, source = folder / f"{name}.h", folder / f"{name}.c"
    for path in (header, source):
        if path.is_dir():
            raise ValueError(f"{str(path)!r} is a folder; export with "
                             f"another name or into another directory")
    header.write_text(_header(obj, w, members, signature), encoding='ascii')
    source.write_text(_source(obj, w, consts, functions, signature, body,
                              reset), encoding='ascii')
    return header, source
