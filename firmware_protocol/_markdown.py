"""Render the Markdown OD reference (``OD.md``): one table per index range, the default PDO
mapping, enumerations and cross-object constraints."""

from __future__ import annotations

from . import current_stability, stability
from .cob_id import RESTRICTED_CAN_IDS
from .emcy_codes import EMCY_CODES
from .entry import Entry
from .index_ranges import RANGES, RPDO_MAP, TPDO_MAP
from .od import ObjectDictionaryView

__all__ = ["MARKDOWN_NAME", "render_markdown"]

MARKDOWN_NAME = "OD.md"


def _int(value: object) -> int:
    """An integer default of the EDS (a PDO's mapped count, references, transmission type,
    event timer); TypeError for anything else."""
    if isinstance(value, int):
        return value
    raise TypeError(f"expected an integer default, got {value!r}")


def _md(text: object) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _md_value(e: Entry, value: float | int | str | bytes | None) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, int) and e.data_type == 0x07 and (value > 0xFFFF or e.relative):
        return f"0x{value:08X}"
    return str(value)


def render_markdown(view: ObjectDictionaryView) -> str:
    """The OD reference page: one table per index range, then enumerations and constraints."""
    out: list[str] = []
    add = out.append
    add("# Object dictionary of the BLDC 5 kW / 48 V drive")
    add("")
    add("Generated from `firmware_protocol/bldc_drive.eds` by")
    add("`python -m firmware_protocol.generate`; do not edit. Names are the Python view names")
    add("(`firmware_protocol.load_od().entry(name)`); C macros in `bldc_drive_od.h` use")
    add("`OD_<OBJECT>__<SUB>_...` (double underscore between record and sub-object).")
    add("Limits are inclusive static limits; `$NODEID` defaults are shown for node-ID 1.")
    add("A nonzero REAL32 must be a normal float32 (|x| >= 1.18e-38; subnormals abort 0x06090030).")
    add("PDO = may be mapped into a PDO (and recorded by the trace).")
    for index_range, title in RANGES:
        rows = [e for e in view.entries if e.index in index_range]
        if not rows:
            continue
        add("")
        add(f"## {title}")
        add("")
        add("| name | index:sub | type | access | unit | default | limits | PDO | description |")
        add("|---|---|---|---|---|---|---|---|---|")
        for e in rows:
            default = _md_value(e, e.default)
            if e.relative:
                default = f"{e.default_raw} ({default})"
            limits = ""
            if e.low is not None or e.high is not None:
                limits = f"[{_md_value(e, e.low)}, {_md_value(e, e.high)}]"
            if e.min_nonzero is not None:
                limits = f"0 or [{_md_value(e, e.min_nonzero)}, {_md_value(e, e.high)}]"
            cells = [
                f"`{e.name}`",
                f"0x{e.index:04X}:{e.subindex:02X}",
                e.type_name,
                e.access,
                e.unit or "",
                default,
                limits,
                "yes" if e.pdo_mappable else "",
                e.description,
            ]
            add("| " + " | ".join(_md(c) for c in cells) + " |")
    add("")
    add("## Default PDO mapping")
    add("")
    add("| PDO | COB-ID | transmission type | event timer | mapped objects (bits) |")
    add("|---|---|---|---|---|")
    for kind, map_base in (("RPDO", RPDO_MAP), ("TPDO", TPDO_MAP)):
        for n in range(512):
            mapping = map_base + n
            try:
                count = view.by_index(mapping, 0).default
            except KeyError:
                break
            comm = mapping - 0x200
            cob = view.by_index(comm, 1)
            ttype = _int(view.by_index(comm, 2).default)
            timer = view.by_index(comm, 5)
            refs = [_int(view.by_index(mapping, i).default) for i in range(1, _int(count or 0) + 1)]
            mapped = ", ".join(f"`{view.by_reference(r).name}` ({r & 0xFF})" for r in refs)
            period = f"{_int(timer.default)} {timer.unit}" if timer.default else "-"
            add(f"| {kind}{n + 1} | {cob.default_raw} | 0x{ttype:02X} | {period} | {mapped} |")
    add("")
    add("## Enumerations")
    add("")
    add("| object | values |")
    add("|---|---|")
    for e in view.entries:
        if e.enum:
            values = ", ".join(f"{v} = {label}" for v, label in sorted(e.enum.items()))
            add(f"| `{e.name}` | {_md(values)} |")
    add("")
    add("## Cross-object constraints")
    add("")
    add("Checked by the drive at every write of either side and by the host before sending;")
    add("a violation aborts with 0x06090031 (bounded object too high) or 0x06090032")
    add("(bound too low).")
    add("")
    add("| rule | reason |")
    add("|---|---|")
    for c in view.constraints:
        add(f"| `{_md(str(c))}` | {_md(c.reason)} |")
    add("")
    add("## Stability rule of the IP speed loop")
    add("")
    add("Checked by the drive when `speed_controller.k_p`/`k_i` is written (with the other's")
    add("present value) and when the staged `gain_set.speed_k_p`/`speed_k_i` are applied")
    add("(`gain_set_apply` 2/3, as a pair; staging is order-free). On the identified model")
    a, b = stability.A_IDENTIFIED, stability.B_IDENTIFIED
    add(f"G(z) = b/(z - a), a = {a}, b = {b} rpm/(A sample),")
    add(f"Ts = {stability.TS * 1e6:g} us, the IP law (eq. 27) gives z^2 + d1 z + d2 with")
    add("d1 = k_p b (1 + k_i) - 1 - a and d2 = a - k_p b. Accepted only if k_p > 0 and k_i > 0")
    add("(else 0x06090032) and k_p k_i b > 0, 2 (1 + a) - k_p b (2 + k_i) > 0, |d2| < 1 (Jury:")
    add("both poles strictly inside the unit circle; else 0x06090031), and the slowest pole")
    add(f"no slower than {stability.TAU_MAX:g} s: |p| <= exp(-Ts / {stability.TAU_MAX:g} s)")
    add("(else 0x06090032). Gains are rounded to float32 first; the poles are computed on")
    add("w = z - 1 without cancellation. A complex pole pair must be damped at least")
    add(f"zeta = -ln|p| / |ln p| >= {stability.ZETA_MIN:g} (else 0x06090031).")
    add("Python: `firmware_protocol.stability.check_ip_speed_gains`.")
    add("")
    cs = current_stability
    add("## Admissibility rule of the current loop and of the cascade")
    add("")
    add("Checked on the whole active set (0x2010:1..10 with motor.R/L/rated_current/")
    add("V_dc_nominal and speed k_p/k_i) at every write of any of them, with the new value in")
    add("place, and on the staged set as a whole when `gain_set_apply` applies it (staging")
    add("0x20F0 is scratch space: any order). On P(z) = Gamma/(z (z - Phi)) (eqs. 4, 5, 8 with")
    add("motor.R, motor.L):")
    add("")
    add(f"1. every closed-loop pole of the current loop inside |z| < rho, rho = max(exp(-Ts / "
        f"{cs.TAU_MAX_CURRENT * 1e3:g} ms),")
    add("   exp(-R Ts / (2 L)), and for deadbeat with R_c > 0 exp(-R_c Ts / (2 L_c))): stable")
    add("   and not slower than 5 ms or than twice a time constant the law itself contains")
    add("   (0x06090031 unstable, 0x06090032 too slow). Deadbeat/predictive: about")
    add("   0.008 < L_c/L < 1.992 (eq. 17: 0 < L_c < 2 L); PI: bounds k_p, k_i;")
    add("2. a law without integral action (predictive, type 2; deadbeat with R_c = 0) needs")
    add("   `emf_feedforward` = 1 (paper: the predictive controller cannot be implemented")
    add("   without feed-forward), else 0x06090030, and L_c >= "
        f"{cs.NO_INTEGRAL_MIN_RATIO:g} L (an unmodelled")
    add("   voltage dV leaves dV / (L_c f_s + 2 R) of current error), else 0x06090032;")
    add("3. predictive: the eq. (25) compensation, if the estimates were entirely wrong,")
    add("   (2 T_BT f_s V_dc + 2 V_G + (T_DD + T_SD) f_s V_dc / 2) / (L_c f_s + 2 R), with")
    add(f"   V_dc = motor.V_dc_nominal, at most {cs.COMP_MAX_SHARE:.0%} of motor.rated_current")
    add("   (else 0x06090031);")
    add("4. the IP speed loop around this current loop (eq. 27 on b/(z - a) times the closed")
    add("   current loop) has every pole inside |z| <= exp(-Ts / 10 s) (else 0x06090031).")
    add("")
    add("Python: `firmware_protocol.current_stability.check_current_gains`, `check_cascade`.")
    add("")
    add("## COB-ID rules (CiA 301)")
    add("")
    add("EMCY 0x1014, SDO server 0x1201:1/2 and PDO 0x1400/0x1800 sub 1 refuse with 0x06090030:")
    add("bit 29 (29-bit frame, not supported), bits 28..11 set, bit 30 on EMCY/SDO (reserved /")
    add("dynamic), a new CAN-ID while the object is valid (write it with bit 31 set first), and")
    add("a valid COB-ID on a restricted CAN-ID: " + ", ".join(
        f"0x{lo:03X}" if lo == hi else f"0x{lo:03X}-0x{hi:03X}" for lo, hi in RESTRICTED_CAN_IDS
    ) + ".")
    add("PDO COB-IDs and mappings change only in PRE-OPERATIONAL (0x08000022 in OPERATIONAL);")
    add("the inhibit time (sub 3) of a valid PDO cannot change (0x06090030). Event-driven TPDOs")
    add("are sent at their event-timer grid point, never before the previous transmission plus")
    add("the inhibit time; periods missed by a late drive are counted in `tpdo_missed_events`.")
    add("0x1016 entries: bits 31..24 reserved (0); time 0 = entry off; node-ID 0 with a time,")
    add("a node-ID above 127 or the drive's own node-ID: 0x06090030; two active entries for the")
    add("same node: 0x06040043. Python: `firmware_protocol.cob_id`.")
    add("")
    add("## Configuration-only objects (power stage off)")
    add("")
    add("They define the plant or its protection (EDS key `ConfigOnly=1`, C macro `_CONFIG_ONLY`);")
    add("a write while the power stage is on (OPERATION ENABLED or a stop ramp running) aborts")
    add("with 0x08000022 and changes nothing.")
    add("")
    add("| name | index:sub |")
    add("|---|---|")
    for e in view.entries:
        if e.config_only:
            add(f"| `{e.name}` | 0x{e.index:04X}:{e.subindex:02X} |")
    add("")
    add("## EMCY codes")
    add("")
    add("| code | C macro | sent when |")
    add("|---|---|---|")
    for code, (stem, when) in sorted(EMCY_CODES.items()):
        add(f"| 0x{code:04X} | `OD_EMCY_{stem}` | {_md(when)} |")
    return "\n".join(out) + "\n"
