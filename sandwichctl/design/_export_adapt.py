"""The C lines of a servo step that estimates its band's gain and the
blend of its two linear feedforwards online (`export_c`; the Python
kernel is `_servo_kernel._blend`, operation for operation)."""


def blend_body(w, ps, lin, oth):
    """The step's lines for the band's gain g and the blend b towards the
    other feedforward, estimated together (`_servo_kernel._blend`)."""
    T, n = w.T, w.name
    one, zero = w.num(1.0), w.num(0.0)
    ps2 = (f"{n}_block({n}_ps_A, {n}_ps_B, {n}_ps_C, {n}_ps_D,\n"
           f"        {ps.n}, s->ps2, d)" if ps.n else f"{n}_ps_D * d")
    return [
        "    {                /* the band's gain and the blend, online */",
        f"        {T} u_lin, d, e, phi_g, phi_b, g, b, pgg, pbb, pbg;",
        f"        {T} hb, hg, den, kb, kg;",
        f"        u_lin = {lin.call(w, 'ra')};",
        f"        d = {oth.call(w, 'ra')} - u_lin;",
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
