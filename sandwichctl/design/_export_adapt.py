"""The C lines of a servo step that adapts online (`export_c`): the
band's gain and the blend of its two linear feedforwards (the Python
kernel is `_servo_kernel._blend`) and the hunting guard's scale on the
feedback (`_servo_kernel._guard`), operation for operation."""

from ._servo_kernel import EARLY, MOTION_TURNS, TURNS


def blend_body(w, ps, lin, oth, r_lin, r_oth):
    """The step's lines for the band's gain g and the blend b towards the
    other feedforward, estimated together (`_servo_kernel._blend`); r_lin
    and r_oth are the C expressions of the two feedforwards' inputs."""
    T, n = w.T, w.name
    one, zero = w.num(1.0), w.num(0.0)
    ps2 = (f"{n}_block({n}_ps_A, {n}_ps_B, {n}_ps_C, {n}_ps_D,\n"
           f"        {ps.n}, s->ps2, d)" if ps.n else f"{n}_ps_D * d")
    return [
        "    {                /* the band's gain and the blend, online */",
        f"        {T} u_lin, d, e, phi_g, phi_b, g, b, pgg, pbb, pbg;",
        f"        {T} hb, hg, den, kb, kg;",
        f"        u_lin = {lin.call(w, r_lin)};",
        f"        d = {oth.call(w, r_oth)} - u_lin;",
        '        e = r_now - yd;',
        f"        phi_g = {ps.call(w, 'u_ff')};",
        f"        phi_b = {ps2};",
        f"        g = {one} + s->band_dg;",
        '        b = s->blend;',
        f"        pgg = {n}_p0 * ({one} - s->band_q);",
        f"        pbb = {n}_pb0 * ({one} - s->blend_q);",
        f"        pbg = {n}_pb0 * s->blend_c;",
        '        hb = pbb * phi_b + pbg * phi_g;',
        '        hg = pbg * phi_b + pgg * phi_g;',
        f"        den = {n}_lam + phi_b * hb + phi_g * hg;",
        '        kb = hb / den;',
        '        kg = hg / den;',
        '        b += kb * e;',
        '        g += kg * e;',
        f"        pbb = (pbb - kb * hb) / {n}_lam;",
        f"        pbg = (pbg - kb * hg) / {n}_lam;",
        f"        pgg = (pgg - kg * hg) / {n}_lam;",
        f"        if (pbb > {n}_pbmax) {{",
        f"            pbg *= {n}_pbmax / pbb;",
        f"            pbb = {n}_pbmax;",
        '        }',
        f"        if (pgg > {n}_pmax) {{",
        f"            pbg *= {n}_pmax / pgg;",
        f"            pgg = {n}_pmax;",
        '        }',
        f"        if (g < {zero})",
        f"            g = {zero};",
        f"        else if (g > {n}_gmax)",
        f"            g = {n}_gmax;",
        f"        if (b < {zero})",
        f"            b = {zero};",
        f"        else if (b > {one})",
        f"            b = {one};",
        f"        s->band_dg = g - {one};",
        f"        s->band_q = {one} - pgg / {n}_p0;",
        '        s->blend = b;',
        f"        s->blend_q = {one} - pbb / {n}_pb0;",
        f"        s->blend_c = pbg / {n}_pb0;",
        '        u_ff *= g;',
        '        u_ff += u_lin;',
        '        u_ff += b * d;',
        '    }']


def guard_parts(w, sc):
    """(state members, constants, step lines) of the hunting guard
    (`_servo_kernel._guard`): the lines scale e, the feedback's error."""
    T, n = w.T, w.name
    one, zero = w.num(1.0), w.num(0.0)
    members = [(f"{T} guard_dc;", "the guard's scale on the feedback, less 1"),
               (f"{T} guard_r;", 'r(k-1), to tell a hold'),
               (f"{T} guard_n;", 'samples into the hold'),
               (f"{T} guard_ext;", 'the last extreme: of y in a hold, of '
                'the error in a move'),
               (f"{T} guard_dir;", 'its direction: -1, 0 or 1'),
               (f"{T} guard_turns;", 'reversals counted'),
               (f"{T} guard_last;", 'the sample of the last one'),
               (f"{T} guard_move;", 'samples into the move (0 in a hold)'),
               (f"{T} guard_step;", "the direction of r's last step")]
    consts = ['/* Hunting guard: reversals of y in a hold, or of the error in '
              'a move, scale the feedback down. */',
              w.const('hunt', sc['hunt'], 'deadband of a reversal'),
              w.const('settle', sc['settle'], 'samples into a hold before '
                      'reversals count (and from half of it, in an early '
                      'window)'),
              w.const('beta', sc['beta'], 'factor on the scale per '
                      f'{TURNS} reversals in a hold, {MOTION_TURNS} in a '
                      'move'),
              w.const('floor', sc['floor'], 'least scale'),
              w.const('gap', sc['gap'], 'most samples between reversals '
                      'counted in a row, over the scale')]
    body = [
        '    {                       /* the hunting guard */',
        f"        {T} move, c, z, t, need, step;",
        '        if (r_now != s->guard_r) {',
        f"            s->guard_n = {zero};",
        '            z = r_now - yd;',
        f"            step = r_now > s->guard_r ? {one} : -{one};",
        f"            if (s->guard_move == {zero}"
        " || step != s->guard_step) {",
        '                s->guard_ext = z;',
        f"                s->guard_dir = {zero};",
        f"                s->guard_turns = {zero};",
        '            }',
        '            s->guard_step = step;',
        f"            s->guard_move += {one};",
        '            t = s->guard_move;',
        f"            need = {w.num(MOTION_TURNS)};",
        '        } else {',
        f"            s->guard_n += {one};",
        f"            s->guard_move = {zero};",
        '            z = yd;',
        '            t = s->guard_n;',
        f"            need = {w.num(TURNS)};",
        '        }',
        '        s->guard_r = r_now;',
        f"        if (s->guard_move == {zero}"
        f" && (s->guard_n < {w.num(EARLY)} * {n}_settle",
        f"            || s->guard_n == {n}_settle - {one})) {{",
        '            s->guard_ext = yd;',
        f"            s->guard_dir = {zero};",
        f"            s->guard_turns = {zero};",
        '        } else {',
        '            move = z - s->guard_ext;',
        f"            if (s->guard_dir * move > {zero})",
        '                s->guard_ext = z;',
        f"            else if ({w.abs}(move) > {n}_hunt) {{",
        f"                if (s->guard_dir != {zero}) {{",
        '                    if (t - s->guard_last',
        f"                        <= {n}_gap / ({one} + s->guard_dc))",
        f"                            s->guard_turns += {one};",
        '                    else',
        f"                            s->guard_turns = {zero};",
        '                }',
        f"                s->guard_dir = move > {zero} ? {one} : -{one};",
        '                s->guard_ext = z;',
        '                s->guard_last = t;',
        '            }',
        '            if (s->guard_turns >= need) {',
        f"                c = ({one} + s->guard_dc) * {n}_beta;",
        f"                if (c < {n}_floor)",
        f"                    c = {n}_floor;",
        f"                s->guard_dc = c - {one};",
        f"                s->guard_turns = {zero};",
        '            }',
        '        }',
        f"        e *= {one} + s->guard_dc;",
        '    }']
    return members, consts, body
