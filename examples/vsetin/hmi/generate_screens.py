#!/usr/bin/env python3
"""Writes the SVG mimics of the Vsetín web HMI (this folder's *.svg).

The screens are plain SVG with the bindings of docs/HMI.md ("SVG bindings"): data-point,
data-energised, data-text, data-command, data-link-status. Colours are not in the files:
they come from classes (hv, lv, breaker, ind, fault, lamp, comm, ...) styled by the HMI's
stylesheet (crates/hmi/web/app.css). The output is meant to be read and edited by hand;
this script only saves typing the repeated boards (RH2/RZZ, thirteen lighting boards).

    python3 examples/vsetin/hmi/generate_screens.py

Point names are those of points.csv (`stanice points examples/vsetin`); the script checks
every name it uses against that file.
"""

import csv
from pathlib import Path
from xml.sax.saxutils import escape, quoteattr

HERE = Path(__file__).resolve().parent
LIGHTING = [f"ROV{k:02d}" for k in range(1, 13)] + ["OR"]

with open(HERE / "points.csv", encoding="utf-8") as f:
    KNOWN = {row["name"]: row for row in csv.DictReader(f)}
USED = set()


def use(name):
    if name not in KNOWN:
        raise SystemExit(f"unknown point or command {name!r} (not in points.csv)")
    USED.add(name)
    return name


class Svg:
    def __init__(self, title, width, height):
        self.lines = [
            '<?xml version="1.0" encoding="UTF-8"?>',
            f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {width} {height}" width="{width}" height="{height}">',
            f"  <title>{escape(title)}</title>",
        ]
        self.depth = 1

    def raw(self, text):
        self.lines.append("  " * self.depth + text)

    def comment(self, text):
        self.raw(f"<!-- {text} -->")

    def open(self, tag, **attrs):
        self.raw(f"<{tag}{attributes(attrs)}>")
        self.depth += 1

    def close(self, tag):
        self.depth -= 1
        self.raw(f"</{tag}>")

    def el(self, tag, text=None, **attrs):
        if text is None:
            self.raw(f"<{tag}{attributes(attrs)}/>")
        else:
            self.raw(f"<{tag}{attributes(attrs)}>{escape(text)}</{tag}>")

    def text(self, x, y, text, cls=None, anchor=None, **attrs):
        self.el("text", text, x=x, y=y, class_=cls, text_anchor=anchor, **attrs)

    def write(self, name):
        self.lines.append("</svg>")
        (HERE / name).write_text("\n".join(self.lines) + "\n", encoding="utf-8")
        print(f"wrote {name}")


def attributes(attrs):
    out = []
    for key, value in attrs.items():
        if value is None:
            continue
        key = key.rstrip("_").replace("_", "-")
        out.append(f" {key}={quoteattr(str(value))}")
    return "".join(out)


# ------------------------------------------------------------------------ symbols
def breaker(svg, x, y, point, label, size=22, command=None, state_text=True, **extra):
    """A switching device: a square, filled when closed (data-point = its 'closed' point)."""
    svg.open("g", id=f"breaker-{label.replace(' ', '-').replace('.', '_')}")
    svg.el("rect", x=x - size / 2, y=y - size / 2, width=size, height=size, rx=2, class_="breaker",
           data_point=use(point), **({"data-command": use(command)} if command else {}), **extra)
    svg.text(x + size / 2 + 6, y - 2, label, "label")
    if state_text:
        svg.text(x + size / 2 + 6, y + 12, "", "value small", data_text=point, data_on="closed", data_off="open")
    svg.close("g")


def indicator(svg, x, y, point, label, cls="ind", r=8, anchor="start"):
    """A round indicator with its label to the right."""
    svg.el("circle", cx=x, cy=y, r=r, class_=cls, data_point=use(point))
    svg.text(x + r + 6, y + 4, label, "label")


def button(svg, x, y, w, label, command, value, state_point=None, h=26, words=None):
    """A control button: a click opens the control dialog for COMMAND with VALUE; `words`
    (default the label) say what it does in the dialog."""
    svg.open("g", class_="control", data_command=use(command), data_command_value=value,
             data_label=words or label, **({"data-state-point": use(state_point)} if state_point else {}))
    svg.el("rect", x=x, y=y, width=w, height=h, rx=5, class_="button")
    svg.text(x + w / 2, y + h / 2 + 4, label, "button-text")
    svg.close("g")


def board_box(svg, x, y, w, h, title, subtitle=None, link=None):
    svg.el("rect", x=x, y=y, width=w, height=h, rx=6, class_="box")
    if link:
        svg.open("a", href=f"#screen/{link}")
        svg.text(x + 10, y + 20, f"{title} ›", "title")
        svg.close("a")
    else:
        svg.text(x + 10, y + 20, title, "title")
    if subtitle:
        svg.text(x + 10, y + 37, subtitle, "label small")


def heading(svg, title, subtitle):
    svg.text(20, 32, title, "title")
    svg.text(20, 52, subtitle, "label")
    svg.el("circle", cx=1040, cy=27, r=7, class_="ind", data_link_status="")
    svg.text(1054, 32, "", "value", data_link_status="")


# ------------------------------------------------------------------------ supply overview
def value(svg, x, y, point, unit, digits="0", cls="value small", anchor=None):
    """A measurement as text."""
    svg.text(x, y, "", cls, anchor, data_text=use(point), data_unit=unit, data_digits=digits)


def supply():
    svg = Svg("Vsetín — power supply overview", 1200, 760)
    heading(svg, "Power supply — technology building TO and transport terminal DT",
            "HV 6 kV yellow, LV 0.4 kV green; dashed grey = no voltage. Click a board for its panel.")

    svg.comment("Control authority (spec 7.4, 9.2): HMI-local vs remote dispatch, point SP 21, command IOA 2001")
    svg.open("g", id="authority")
    svg.el("rect", x=790, y=62, width=390, height=92, rx=8, class_="authority",
           data_point=use("RDRT_SP21_HMI_Mistne"))
    svg.text(805, 84, "Control authority", "label")
    svg.text(805, 110, "", "value", data_text="RDRT_SP21_HMI_Mistne",
             data_on="LOCAL — operation from this HMI", data_off="REMOTE — dispatch (DDTS, DŘT)",
             font_size=15)
    button(svg, 805, 120, 170, "Take local control", "RDRT_HMI_Mistne", 1, "RDRT_SP21_HMI_Mistne")
    button(svg, 990, 120, 175, "Give to dispatch", "RDRT_HMI_Mistne", 0, "RDRT_SP21_HMI_Mistne")
    svg.close("g")

    svg.comment("6 kV: the lines from the traction substations, switchroom R6 (incomers Q1, Q2,"
                " transformer feeder Q3) and the by-pass RS602 (spec 2.2); the voltages as numbers")
    svg.open("g", id="hv", transform="translate(0 -4)")
    svg.open("a", href="#screen/rh11")
    svg.text(70, 84, "TNS Ústí R6kV ›", "label")
    svg.text(330, 84, "TNS Valašské Meziříčí R6kV ›", "label")
    svg.close("a")
    svg.el("path", d="M 110 92 V 111 M 110 133 V 160", class_="hv")
    svg.el("path", d="M 420 92 V 111 M 420 133 V 160", class_="hv")
    breaker(svg, 110, 122, "R6_Q1_Zapnut", "Q1", size=16, state_text=False)
    breaker(svg, 420, 122, "R6_Q2_Zapnut", "Q2", size=16, state_text=False)
    svg.el("path", d="M 90 160 H 520", class_="hv bus", id="bus-R6")
    svg.text(440, 154, "R6", "label")
    value(svg, 470, 154, "R6_U", "V")
    svg.el("path", d="M 265 160 V 171 M 265 189 V 200", class_="hv")
    breaker(svg, 265, 180, "R6_Q3_Zapnut", "Q3", size=16, state_text=False)
    svg.el("path", d="M 110 100 H 40 V 171 M 40 189 V 200 H 130", class_="hv", stroke_dasharray="6 3")
    breaker(svg, 40, 180, "RS602_Zapnut", "RS602", size=16, state_text=False)
    svg.el("path", d="M 130 200 H 400", class_="hv bus", id="bus-R6_T")
    value(svg, 290, 196, "R6_T_U", "V")
    svg.close("g")

    svg.comment("Transformers: T1 (the thesis's TZ1) feeds RZZ (KHU1 of RZZ), T2 feeds RH2 (KHU1 of RH2)")
    for name, x, board in [("T1 (TZ1)", 150, "RZZ"), ("T2", 380, "RH2")]:
        khu1 = f"{board}_P1_KHU1_Napeti_na_privodu"
        svg.open("g", id=f"transformer-{name.split()[0]}")
        svg.el("path", d=f"M {x} 196 V 212", class_="hv", data_energised=use(khu1))
        svg.el("circle", cx=x, cy=225, r=13, class_="transformer")
        svg.el("circle", cx=x, cy=244, r=13, class_="transformer")
        svg.text(x + 20, 240, f"{name} 6/0.4 kV", "label small")
        svg.el("path", d=f"M {x} 257 V 300", class_="lv", data_energised=khu1)
        svg.close("g")

    for board, x, subtitle, screen in [("RZZ", 60, "signalling board, LOGO!", "rzz"),
                                       ("RH2", 290, "main distribution, LOGO!", "rh2")]:
        svg.comment(f"Board {board}; QF1 shown by the voltage behind it (KHU3)")
        svg.open("g", id=f"board-{board}")
        p = f"{board}_P1_"
        board_box(svg, x, 300, 200, 150, board, subtitle, link=screen)
        breaker(svg, x + 90, 360, f"{p}KHU3_Napeti_na_pripojeni", "QF1", state_text=False)
        svg.el("path", d=f"M {x + 90} 300 V 349", class_="lv", data_energised=f"{p}KHU1_Napeti_na_privodu")
        svg.el("path", d=f"M {x + 20} 410 H {x + 180}", class_="lv bus", data_energised=use(f"{p}KHU3_Napeti_na_pripojeni"))
        svg.el("path", d=f"M {x + 90} 371 V 410", class_="lv", data_energised=f"{p}KHU3_Napeti_na_pripojeni")
        indicator(svg, x + 20, 435, f"{p}KHV{board}_Havarijni_vypnuti", "emergency off", "fault", 6)
        svg.text(x + 130, 381, "", "value small", data_text=use(f"{p}SA1_Dalkove"), data_on="remote", data_off="LOCAL")
        svg.close("g")

    svg.comment("The signalling equipment's universal source (spec 2.2): from RZZ (K1), backup from RZS1 (K2)")
    svg.open("g", id="signalling-supply")
    svg.el("path", d="M 110 410 V 529", class_="lv", data_energised=use("UZ_Napeti_RZZ"))
    board_box(svg, 60, 490, 200, 120, "Signalling supply", None, link="rzs1")
    breaker(svg, 110, 540, "UZ_K1_Zapnut", "K1", size=18, state_text=False)
    breaker(svg, 200, 540, "UZ_K2_Zapnut", "K2", size=18, state_text=False)
    svg.el("path", d="M 110 549 V 575 M 200 549 V 575", class_="lv", data_energised=use("UZ_Vystup"))
    svg.el("path", d="M 80 575 H 240", class_="lv bus", data_energised="UZ_Vystup")
    svg.text(80, 598, "", "value small", data_text="UZ_Vystup", data_on="supplied", data_off="NOT SUPPLIED")
    value(svg, 250, 562, "SZZ_P_kW", "kW", "1", anchor="end")
    svg.close("g")

    svg.comment("Board RH1.1: main board on the utility connection; RDA's mains input (KHU1 of RDA), RH1.2 and RH in DT")
    svg.open("g", id="board-RH1.1")
    svg.text(560, 258, "utility connection (distribution)", "label")
    svg.el("path", d="M 640 265 V 300", class_="lv", data_energised=use("RH11_KHU1_Napeti_sit"))
    board_box(svg, 540, 300, 200, 110, "RH1.1", "main board, S7-1500", link="rh11")
    svg.el("path", d="M 560 360 H 720", class_="lv bus", data_energised="RDA_KHU1_NapetiSit")
    svg.text(560, 390, "autoblock supply, RDA mains", "label small")
    value(svg, 730, 337, "RH11_P_kW", "kW", "1", anchor="end")
    svg.el("path", d="M 587 360 V 460 M 693 360 V 460", class_="lv", data_energised="RDA_KHU1_NapetiSit")
    for x, title, screen, live in [(540, "RH1.2", "rh12", "RH12_P1_KHU3_Napeti_na_pripojeni"),
                                   (646, "RH (DT)", "dt", "RHDT_KHU1_Napeti")]:
        board_box(svg, x, 460, 94, 60, title, None, link=screen)
        indicator(svg, x + 14, 505, live, "live", "ind", 6)
    svg.close("g")

    svg.comment("RDA: automatic transfer mains (KM1) / diesel generator (KM2) to the secured board RZS")
    svg.open("g", id="board-RDA")
    board_box(svg, 790, 250, 390, 250, "RDA", "transfer mains ↔ diesel, LOGO!", link="rda")
    svg.el("path", d="M 720 360 H 770 V 470 H 850 V 445", class_="lv", data_energised="RDA_KHU1_NapetiSit")
    breaker(svg, 850, 430, "RDA_KM1_Zapnut", "KM1 mains")
    svg.el("circle", cx=1090, cy=320, r=24, class_="box", id="generator")
    svg.text(1090, 326, "G", "title", "middle")
    svg.text(1122, 318, "DA", "label")
    indicator(svg, 1010, 292, "RDA_DA_Bezi", "running", "ind", 6)
    svg.el("path", d="M 1090 344 V 380 H 1000 V 415", class_="lv", data_energised=use("RDA_KHU2_NapetiDA"))
    breaker(svg, 1000, 430, "RDA_KM2_Zapnut", "KM2 diesel")
    svg.text(810, 318, "transfer state:", "label")
    svg.text(810, 338, "", "value", data_text=use("RDA_Stav"),
             data_map="0:starting;1:on mains;2:generator starting;3:settling;4:on generator;5:returning to mains;9:EMERGENCY OFF")
    indicator(svg, 816, 362, "RDA_Porucha", "transfer fault", "fault", 6)
    svg.close("g")

    svg.comment("RZS / RZS1: the secured network, fed through KM1 or KM2 (busbar voltage KHU3 of RDA);"
                " RZS2 and RZS in DT hang off it, and the signalling supply's backup K2")
    svg.open("g", id="board-RZS")
    svg.el("path", d="M 850 441 V 470 M 1000 441 V 470", class_="lv", data_energised=use("RDA_KHU3_NapetiRZS"))
    svg.el("path", d="M 820 470 H 1160", class_="lv bus", data_energised="RDA_KHU3_NapetiRZS")
    svg.el("path", d="M 990 470 V 540", class_="lv", data_energised="RDA_KHU3_NapetiRZS")
    board_box(svg, 890, 540, 220, 90, "RZS / RZS1", "secured network, S7-1500", link="rzs1")
    indicator(svg, 905, 600, "RDA_BezNapeti", "RZS without supply", "fault", 6)
    svg.el("path", d="M 890 620 H 200 V 551", class_="lv", data_energised=use("UZ_Napeti_RZS1"))
    svg.el("path", d="M 940 630 V 660 M 1060 630 V 660", class_="lv", data_energised="RDA_KHU3_NapetiRZS")
    for x, title, screen, live in [(893, "RZS2", "rzs2", "RZS2_P1_KHU3_Napeti_na_pripojeni"),
                                   (1013, "RZS (DT)", "dt", "RZSDT_KHU1_Napeti")]:
        board_box(svg, x, 660, 94, 60, title, None, link=screen)
        indicator(svg, x + 14, 705, live, "live", "ind", 6)
    svg.close("g")

    svg.comment("Legend")
    svg.open("g", id="legend", transform="translate(40 700)")
    svg.el("path", d="M 0 0 H 40", class_="hv")
    svg.text(48, 4, "6 kV", "label")
    svg.el("path", d="M 100 0 H 140", class_="lv")
    svg.text(148, 4, "0.4 kV", "label")
    svg.el("rect", x=210, y=-8, width=16, height=16, class_="breaker", data_value="on")
    svg.text(232, 4, "closed", "label")
    svg.el("rect", x=290, y=-8, width=16, height=16, class_="breaker", data_value="off")
    svg.text(312, 4, "open", "label")
    svg.text(0, 30, "blinking magenta = invalid (no current value)", "label")
    svg.close("g")
    svg.write("supply.svg")


# ------------------------------------------------------------------------ RH2 / RZZ panels
def meters(svg, x, y, board, title="Meter"):
    """A board's meter: voltage, current, power, energy."""
    svg.open("g", id=f"meter-{board}")
    svg.el("rect", x=x, y=y, width=330, height=120, rx=6, class_="frame")
    svg.text(x + 15, y + 22, title, "title")
    for i, (suffix, label, unit, digits) in enumerate([("U", "voltage", "V", "0"), ("I_A", "current", "A", "1"),
                                                       ("P_kW", "power", "kW", "1"),
                                                       ("Energie_kWh", "energy", "kWh", "1")]):
        row_y = y + 46 + i * 20
        svg.text(x + 15, row_y, label, "label")
        value(svg, x + 200, row_y, f"{board}_{suffix}", unit, digits, "value", "end")
    svg.close("g")


def power_board(board, fed_from, concentrator, comm_upper, name=None, feeders=None):
    """A LOGO! board's panel; `name` is the thesis's (RH1.2) where the prefix differs;
    `feeders` names what FA1.1 .. FA1.5 feed (spare where not given)."""
    feeders = feeders or ["spare"] * 5
    name = name or board
    svg = Svg(f"Vsetín — board {name}", 1200, 720)
    p = f"{board}_P1_"
    v = f"{board}_V1_"
    heading(svg, f"Board {name} — fed from {fed_from}",
            f"LOGO! reporting through {concentrator}; QF1 operated from here only with SA1 in remote and HMI authority local.")

    svg.comment("Communication: the LOGO! link and the concentrator link (TRUE = failure)")
    svg.open("g", id="communication")
    indicator(svg, 40, 85, f"COMM_{board}", f"link {concentrator} → {name} failed", "fault")
    indicator(svg, 340, 85, comm_upper, f"link RDRT → {concentrator} failed", "fault")
    svg.close("g")
    meters(svg, 830, 110, board, f"Meter of {name}")

    svg.comment(f"Incoming feeder from {fed_from} (KHU1), feeder breaker QF1, busbar (KHU3)")
    svg.open("g", id="feeder")
    svg.text(60, 130, f"from {fed_from}", "label")
    svg.el("path", d="M 120 140 V 210", class_="lv", data_energised=use(f"{p}KHU1_Napeti_na_privodu"))
    indicator(svg, 150, 175, f"{p}KHU1_Napeti_na_privodu", "voltage on feeder (KHU1)")
    svg.comment("QF1 has no auxiliary contact point: its state is the voltage behind it (KHU3)")
    svg.open("g", id="QF1")
    svg.el("rect", x=100, y=210, width=40, height=40, rx=3, class_="breaker",
           data_point=use(f"{p}KHU3_Napeti_na_pripojeni"))
    svg.text(150, 228, "QF1", "title")
    svg.text(150, 246, "", "value small", data_text=f"{p}KHU3_Napeti_na_pripojeni",
             data_on="closed (voltage behind)", data_off="open (no voltage)")
    svg.close("g")
    button(svg, 330, 205, 110, "Open QF1", use(f"{board}_VypnoutQF1"), 1, f"{p}KHU3_Napeti_na_pripojeni")
    button(svg, 330, 238, 110, "Close QF1", use(f"{board}_ZapnoutQF1"), 1, f"{p}KHU3_Napeti_na_pripojeni")
    svg.el("path", d="M 120 250 V 300", class_="lv", data_energised=use(f"{p}KHU3_Napeti_na_pripojeni"))
    svg.el("path", d="M 60 300 H 760", class_="lv bus", data_energised=f"{p}KHU3_Napeti_na_pripojeni")
    indicator(svg, 780, 304, f"{p}KHU3_Napeti_na_pripojeni", "busbar voltage (KHU3)")
    svg.close("g")

    svg.comment("Outgoing breakers FA1, FA1.1 .. FA1.5 (filled = closed)")
    svg.open("g", id="outgoing")
    outgoing = [("FA1", f"{v}FA1_Zapnut")] + [(f"FA1.{i}", f"{v}FA1.{i}") for i in range(1, 6)]
    for i, (label, point) in enumerate(outgoing):
        x = 100 + i * 110
        svg.el("path", d=f"M {x} 300 V 349", class_="wire")
        breaker(svg, x, 360, point, label)
        svg.el("path", d=f"M {x} 371 V 420", class_="wire")
        if i > 0:
            svg.text(x, 436, feeders[i - 1], "label feeder", "middle")
    svg.close("g")

    svg.comment("110 V DC section: source G110.2, breakers FA110.0 .. FA110.2, surge arrester FV110")
    svg.open("g", id="dc110")
    svg.el("rect", x=40, y=450, width=520, height=170, rx=6, class_="frame")
    svg.text(55, 472, "110 V DC", "title")
    indicator(svg, 170, 467, f"{p}G110.2_Napeti_zdroje", "source G110.2 voltage")
    svg.el("path", d="M 60 500 H 540", class_="wire", stroke_width=4)
    for i in range(3):
        x = 110 + i * 150
        svg.el("path", d=f"M {x} 500 V 529", class_="wire")
        breaker(svg, x, 540, f"{p}FA110.{i}", f"FA110.{i}")
    indicator(svg, 60, 598, f"{p}FV110_Prepetova_ochrana", "surge arrester FV110 tripped", "warn")
    svg.close("g")

    svg.comment("Protection and selector")
    svg.open("g", id="protection")
    svg.el("rect", x=600, y=450, width=560, height=170, rx=6, class_="frame")
    svg.text(615, 472, "Protection and control", "title")
    svg.el("circle", cx=640, cy=510, r=18, class_="fault", data_point=use(f"{p}KHV{board}_Havarijni_vypnuti"))
    svg.text(668, 508, "EMERGENCY OFF", "title")
    svg.text(668, 526, "", "value small", data_text=f"{p}KHV{board}_Havarijni_vypnuti",
             data_on="pressed — QF1 held open", data_off="not pressed")
    indicator(svg, 630, 560, f"{p}FU1_Pretavena_pojistka", "fuse FU1 blown", "warn")
    indicator(svg, 630, 590, f"{p}FV1_Prepetova_ochrana", "surge arrester FV1 tripped", "warn")
    svg.text(900, 555, "Selector SA1", "label")
    svg.text(900, 578, "", "value", data_text=use(f"{p}SA1_Dalkove"),
             data_on="REMOTE (PLC controls QF1)", data_off="LOCAL (door pushbuttons)")
    indicator(svg, 900, 600, f"{p}SA1_Mistne", "local")
    indicator(svg, 990, 600, f"{p}SA1_Dalkove", "remote")
    svg.close("g")

    svg.comment("Authority reminder: commands pass only in HMI-local mode for this HMI link")
    svg.text(20, 690, "", "label", data_text="RDRT_SP21_HMI_Mistne",
             data_on="Control authority: LOCAL (this HMI)", data_off="Control authority: REMOTE dispatch")
    svg.write(f"{board.lower()}.svg")


# ------------------------------------------------------------------------ RDA / RZS panel
def rda():
    svg = Svg("Vsetín — boards RZS1 and RDA", 1200, 720)
    heading(svg, "Boards RZS1 / RDA — transfer mains ↔ diesel generator",
            "KM1 and KM2 are never closed together; the generator's voltage settles before KM2 closes (spec 5.3).")
    svg.comment("Communication")
    svg.open("g", id="communication")
    indicator(svg, 40, 85, "COMM_RDA", "link RZS1 → RDA failed", "fault")
    indicator(svg, 300, 85, "COMM_RZS", "link RDRT → RZS1 failed", "fault")
    svg.close("g")

    svg.comment("Mains from RH1.1 through KM1")
    svg.open("g", id="mains")
    svg.text(80, 130, "mains from RH1.1", "label")
    svg.el("path", d="M 140 140 V 250", class_="lv", data_energised=use("RDA_KHU1_NapetiSit"))
    indicator(svg, 165, 180, "RDA_KHU1_NapetiSit", "mains voltage (KHU1)")
    breaker(svg, 140, 270, "RDA_KM1_Zapnut", "KM1", size=36)
    indicator(svg, 200, 300, "RDA_Porucha_KM1", "KM1 does not follow its coil", "fault", 6)
    svg.el("path", d="M 140 288 V 360", class_="lv", data_energised=use("RDA_KHU3_NapetiRZS"))
    svg.close("g")

    svg.comment("Diesel generator DA through KM2")
    svg.open("g", id="generator")
    svg.el("circle", cx=560, cy=160, r=34, class_="box")
    svg.text(560, 168, "G", "title", "middle", font_size=24)
    svg.text(604, 140, "Diesel generator DA", "title")
    indicator(svg, 610, 165, "RDA_DA_Bezi", "running")
    indicator(svg, 610, 190, "RDA_DA_Pripraven", "ready (voltage settled)")
    indicator(svg, 800, 165, "RDA_DA_Porucha", "failed to start", "fault")
    indicator(svg, 800, 190, "RDA_Porucha_DA", "generator fault", "fault")
    svg.el("path", d="M 560 194 V 250", class_="lv", data_energised=use("RDA_KHU2_NapetiDA"))
    indicator(svg, 585, 225, "RDA_KHU2_NapetiDA", "generator voltage (KHU2)")
    breaker(svg, 560, 270, "RDA_KM2_Zapnut", "KM2", size=36)
    indicator(svg, 620, 300, "RDA_Porucha_KM2", "KM2 does not follow its coil", "fault", 6)
    svg.el("path", d="M 560 288 V 360", class_="lv", data_energised="RDA_KHU3_NapetiRZS")
    svg.close("g")

    svg.comment("RZS busbar")
    svg.open("g", id="rzs-bus")
    svg.el("path", d="M 80 360 H 760", class_="lv bus", data_energised="RDA_KHU3_NapetiRZS")
    indicator(svg, 780, 364, "RDA_KHU3_NapetiRZS", "RZS busbar voltage (KHU3)")
    svg.text(80, 390, "secured network RZS (RZS1 / RZS2, backup of RZZ)", "label")
    svg.close("g")

    svg.comment("Transfer state machine (RDA_Stav) and the test-run command")
    svg.open("g", id="transfer")
    svg.el("rect", x=40, y=420, width=560, height=200, rx=6, class_="frame")
    svg.text(55, 442, "Transfer", "title")
    svg.text(55, 470, "state:", "label")
    svg.text(100, 470, "", "value", data_text="RDA_Stav", font_size=16,
             data_map="0:starting;1:MAINS;2:generator starting;3:generator settling;4:ON GENERATOR;5:returning to mains;9:EMERGENCY OFF")
    svg.text(360, 470, "", "label small", data_text="RDA_Stav", data_digits="0", data_unit="(code)")
    indicator(svg, 60, 500, "RDA_NaSiti", "RZS fed from the mains")
    indicator(svg, 60, 525, "RDA_NaDA", "RZS fed from the generator", "warn")
    indicator(svg, 60, 550, "RDA_BezNapeti", "RZS without supply", "fault")
    indicator(svg, 60, 575, "RDA_Porucha", "transfer fault (summary)", "fault")
    indicator(svg, 320, 500, "RDA_HavarijniVyp", "emergency off", "fault")
    indicator(svg, 320, 525, "RDA_FU1_PretavenaPojistka", "fuse FU1 blown", "warn")
    indicator(svg, 320, 550, "RDA_FV1_PrepetovaOchrana", "surge arrester FV1", "warn")
    svg.close("g")

    svg.open("g", id="test-run")
    svg.el("rect", x=640, y=420, width=520, height=200, rx=6, class_="frame")
    svg.text(655, 442, "Generator test run (RDA_ProvozDA)", "title")
    svg.text(655, 468, "Runs RZS from the generator until ended; needs SA1 in remote and HMI authority local.", "label small")
    button(svg, 655, 485, 200, "Start test run", "RDA_ProvozDA", 1, "RDA_NaDA")
    button(svg, 875, 485, 200, "End test run", "RDA_ProvozDA", 0, "RDA_NaDA")
    svg.text(655, 545, "Selector SA1:", "label")
    svg.text(750, 545, "", "value", data_text=use("RDA_SA1_Dalkove"), data_on="REMOTE", data_off="LOCAL")
    indicator(svg, 660, 575, "RDA_SA1_Mistne", "local")
    indicator(svg, 760, 575, "RDA_SA1_Dalkove", "remote")
    svg.close("g")
    svg.text(20, 690, "", "label", data_text="RDRT_SP21_HMI_Mistne",
             data_on="Control authority: LOCAL (this HMI)", data_off="Control authority: REMOTE dispatch")
    svg.write("rda.svg")


# ------------------------------------------------------------------------ RH1.1 and R6
def screen_link(svg, x, y, label, screen, cls):
    """A centred label, a link to `screen` unless it is None."""
    if screen:
        svg.open("a", href=f"#screen/{screen}")
    svg.text(x, y, label, cls, "middle")
    if screen:
        svg.close("a")


def rh11():
    svg = Svg("Vsetín — board RH1.1 and the 6 kV switchroom R6", 1200, 720)
    heading(svg, "Board RH1.1 and the 6 kV switchroom R6",
            "R6's cubicles and the by-pass RS602 are operated by hand on site; RS602 closes only with Q3 open.")
    svg.open("g", id="communication")
    indicator(svg, 40, 85, "COMM_RH", "link RDRT → RH1.1 failed", "fault")
    indicator(svg, 300, 85, "COMM_RH2", "link RH1.1 → RH2 failed", "fault")
    indicator(svg, 560, 85, "COMM_RH12", "link RH1.1 → RH1.2 failed", "fault")
    svg.close("g")

    svg.comment("6 kV switchroom R6: incomers Q1 (TNS Ústí), Q2 (TNS Valašské Meziříčí), transformer"
                " feeder Q3; by-pass disconnector box RS602 from the Ústí line to the transformers")
    svg.open("g", id="r6")
    svg.el("rect", x=30, y=110, width=560, height=330, rx=6, class_="frame")
    svg.text(45, 132, "6 kV switchroom R6", "title")
    svg.text(110, 160, "line from TNS Ústí", "label")
    svg.text(340, 160, "line from TNS Valašské Meziříčí", "label")
    svg.el("path", d="M 180 168 V 209 M 180 231 V 270", class_="hv")
    svg.el("path", d="M 420 168 V 209 M 420 231 V 270", class_="hv")
    breaker(svg, 180, 220, "R6_Q1_Zapnut", "Q1")
    breaker(svg, 420, 220, "R6_Q2_Zapnut", "Q2")
    svg.el("path", d="M 140 270 H 500", class_="hv bus")
    svg.text(510, 266, "R6", "title")
    value(svg, 510, 286, "R6_U", "V", cls="value")
    svg.el("path", d="M 300 270 V 319 M 300 341 V 390", class_="hv")
    breaker(svg, 300, 330, "R6_Q3_Zapnut", "Q3")
    svg.el("path", d="M 180 185 H 70 V 319 M 70 341 V 390 H 140", class_="hv", stroke_dasharray="6 3")
    breaker(svg, 70, 330, "RS602_Zapnut", "RS602")
    svg.el("path", d="M 140 390 H 500", class_="hv bus")
    svg.text(510, 386, "to T1 (TZ1), T2", "label")
    value(svg, 510, 406, "R6_T_U", "V", cls="value")
    svg.open("a", href="#screen/rzz")
    svg.text(160, 425, "T1 → RZZ ›", "label")
    svg.close("a")
    svg.open("a", href="#screen/rh2")
    svg.text(380, 425, "T2 → RH2 ›", "label")
    svg.close("a")
    svg.close("g")

    svg.comment("RH1.1: utility feed, QF1, busbar, protection; outgoing to RDA (mains), RH1.2, RH in DT, autoblock")
    svg.open("g", id="rh11")
    svg.el("rect", x=620, y=250, width=560, height=190, rx=6, class_="frame")
    svg.text(635, 272, "RH1.1 — main board (S7-1500)", "title")
    svg.text(640, 296, "utility connection", "label")
    svg.el("path", d="M 680 305 V 339 M 680 361 V 390", class_="lv", data_energised=use("RH11_KHU1_Napeti_sit"))
    breaker(svg, 680, 350, "RH11_QF1_Zapnut", "QF1")
    indicator(svg, 800, 300, "RH11_KHU1_Napeti_sit", "utility voltage (KHU1)")
    svg.el("path", d="M 640 390 H 1160", class_="lv bus", data_energised="RH11_KHU1_Napeti_sit")
    for x, label, screen in [(780, "RDA (mains) ›", "rda"), (900, "RH1.2 ›", "rh12"), (1010, "RH in DT ›", "dt"),
                             (1110, "autoblock", None)]:
        svg.el("path", d=f"M {x} 390 V 410", class_="lv", data_energised="RH11_KHU1_Napeti_sit")
        screen_link(svg, x, 426, label, screen, "label small")
    indicator(svg, 800, 325, "RH11_FU1_Pretavena_pojistka", "fuse FU1 blown", "warn")
    indicator(svg, 800, 350, "RH11_FV1_Prepetova_ochrana", "surge arrester FV1 tripped", "warn")
    svg.close("g")
    meters(svg, 830, 110, "RH11", "Meter of RH1.1")
    svg.text(20, 690, "", "label", data_text="RDRT_SP21_HMI_Mistne",
             data_on="Control authority: LOCAL (this HMI)", data_off="Control authority: REMOTE dispatch")
    svg.write("rh11.svg")


# ------------------------------------------------------------------------ RZS1 and the signalling supply
def rzs1():
    svg = Svg("Vsetín — board RZS1 and the signalling supply", 1200, 720)
    heading(svg, "Board RZS1 and the signalling equipment's supply",
            "The universal source takes RZZ (TZ1 from the 6 kV level) and falls back to RZS1; never both.")
    svg.open("g", id="communication")
    for i, (point, label) in enumerate([("COMM_RZS", "link RDRT → RZS1 failed"),
                                        ("COMM_RZZ", "link RZS1 → RZZ failed"),
                                        ("COMM_RDA", "link RZS1 → RDA failed"),
                                        ("COMM_RZS2", "link RZS1 → RZS2 failed")]):
        indicator(svg, 40 + i * 270, 85, point, label, "fault")
    svg.close("g")

    svg.comment("RZS1: the secured-network board, fed by RDA (mains or diesel)")
    svg.open("g", id="rzs1")
    svg.el("rect", x=30, y=110, width=760, height=200, rx=6, class_="frame")
    svg.text(45, 132, "RZS1 — secured network (S7-1500)", "title")
    svg.open("a", href="#screen/rda")
    svg.text(60, 160, "from RDA (mains KM1 / diesel KM2) ›", "label")
    svg.close("a")
    svg.el("path", d="M 120 168 V 230", class_="lv", data_energised=use("RZS1_KHU1_Napeti"))
    svg.el("path", d="M 60 230 H 760", class_="lv bus", data_energised="RZS1_KHU1_Napeti")
    indicator(svg, 150, 200, "RZS1_KHU1_Napeti", "busbar voltage (KHU1)")
    indicator(svg, 420, 160, "RZS1_FU1_Pretavena_pojistka", "fuse FU1 blown", "warn")
    indicator(svg, 420, 185, "RZS1_FV1_Prepetova_ochrana", "surge arrester FV1 tripped", "warn")
    for x, label, screen in [(200, "RZS2 ›", "rzs2"), (400, "RZS in DT ›", "dt"), (600, "signalling (K2)", None)]:
        svg.el("path", d=f"M {x} 230 V 260", class_="lv", data_energised="RZS1_KHU1_Napeti")
        screen_link(svg, x, 278, label, screen, "label")
    svg.close("g")
    meters(svg, 830, 110, "RZS1", "Meter of RZS1")

    svg.comment("The universal source: K1 from RZZ (TZ1), K2 from RZS1 (backup), output to the signalling equipment")
    svg.open("g", id="universal-source")
    svg.el("rect", x=30, y=340, width=760, height=290, rx=6, class_="frame")
    svg.text(45, 362, "Signalling equipment — universal source", "title")
    svg.open("a", href="#screen/rzz")
    svg.text(90, 392, "from RZZ (T1 = TZ1 6/0.4 kV) ›", "label")
    svg.close("a")
    svg.text(430, 392, "backup from RZS1", "label")
    svg.el("path", d="M 200 400 V 459", class_="lv", data_energised=use("UZ_Napeti_RZZ"))
    svg.el("path", d="M 500 400 V 459", class_="lv", data_energised=use("UZ_Napeti_RZS1"))
    indicator(svg, 220, 430, "UZ_Napeti_RZZ", "input live")
    indicator(svg, 520, 430, "UZ_Napeti_RZS1", "input live")
    breaker(svg, 200, 475, "UZ_K1_Zapnut", "K1", size=30)
    breaker(svg, 500, 475, "UZ_K2_Zapnut", "K2", size=30)
    svg.el("path", d="M 200 490 V 540 M 500 490 V 540", class_="lv", data_energised=use("UZ_Vystup"))
    svg.el("path", d="M 120 540 H 640", class_="lv bus", data_energised="UZ_Vystup")
    svg.text(120, 570, "", "value", data_text="UZ_Vystup", data_on="signalling equipment supplied",
             data_off="SIGNALLING EQUIPMENT NOT SUPPLIED", font_size=15)
    svg.text(120, 595, "", "value small", data_text="UZ_K2_Zapnut", data_on="on the backup supply (RZS1)",
             data_off="")
    svg.text(520, 600, "power", "label")
    value(svg, 640, 600, "SZZ_P_kW", "kW", "1", "value", "end")
    svg.close("g")
    svg.text(20, 690, "", "label", data_text="RDRT_SP21_HMI_Mistne",
             data_on="Control authority: LOCAL (this HMI)", data_off="Control authority: REMOTE dispatch")
    svg.write("rzs1.svg")


# ------------------------------------------------------------------------ DT
def dt():
    svg = Svg("Vsetín — transport terminal DT", 1200, 720)
    heading(svg, "Transport terminal DT — boards RH and RZS, OŘ-area lighting",
            "Three S7-1500s, each on its own IEC 104 link to RDRT; the incoming breakers are operated by hand.")
    for i, (board, title, feed, comm, screen) in enumerate([
            ("RHDT", "RH in DT", "from RH1.1 (mains)", "COMM_RH_DT", "rh11"),
            ("RZSDT", "RZS in DT", "from RZS (secured network)", "COMM_RZS_DT", "rzs1")]):
        x = 30 + i * 590
        svg.comment(f"{title}: link, incoming QF1, busbar, protection, meter")
        svg.open("g", id=f"board-{board}")
        svg.el("rect", x=x, y=80, width=560, height=470, rx=6, class_="frame")
        svg.text(x + 15, 104, f"{title} (S7-1500)", "title")
        indicator(svg, x + 300, 100, comm, "link to RDRT failed", "fault")
        svg.open("a", href=f"#screen/{screen}")
        svg.text(x + 40, 140, f"{feed} ›", "label")
        svg.close("a")
        svg.el("path", d=f"M {x + 100} 150 V 204 M {x + 100} 226 V 270", class_="lv",
               data_energised=use(f"{board}_KHU1_Napeti"))
        breaker(svg, x + 100, 215, f"{board}_QF1_Zapnut", "QF1")
        svg.el("path", d=f"M {x + 40} 270 H {x + 520}", class_="lv bus", data_energised=f"{board}_KHU1_Napeti")
        indicator(svg, x + 260, 200, f"{board}_KHU1_Napeti", "busbar voltage (KHU1)")
        indicator(svg, x + 260, 225, f"{board}_FU1_Pretavena_pojistka", "fuse FU1 blown", "warn")
        indicator(svg, x + 260, 250, f"{board}_FV1_Prepetova_ochrana", "surge arrester FV1 tripped", "warn")
        svg.close("g")
        meters(svg, x + 40, 300, board, f"Meter of {title}")

    svg.comment("The third S7-1500 in DT runs the OŘ-area lighting (spec 2.1, 3.1)")
    svg.open("g", id="or-lighting")
    svg.el("rect", x=30, y=570, width=1150, height=110, rx=6, class_="frame")
    svg.open("a", href="#screen/lighting")
    svg.text(45, 594, "OŘ-area lighting (S7-1500) ›", "title")
    svg.close("a")
    indicator(svg, 60, 625, "COMM_OR", "link to RDRT failed", "fault")
    svg.el("circle", cx=330, cy=621, r=12, class_="lamp", data_point=use("OR_PrRele"))
    svg.text(350, 626, "", "value", data_text=use("OR_Osv_Zap"), data_on="lighting ON", data_off="lighting off")
    svg.text(600, 626, "power", "label")
    value(svg, 720, 626, "OR_P_kW", "kW", "1", "value", "end")
    svg.text(780, 626, "energy", "label")
    value(svg, 920, 626, "OR_Energie_kWh", "kWh", "1", "value", "end")
    svg.close("g")
    svg.write("dt.svg")


# ------------------------------------------------------------------------ lighting
def lighting():
    cols, w, h = 5, 232, 222
    svg = Svg("Vsetín — outdoor lighting", 1200, 90 + 3 * (h + 10) + 10)
    heading(svg, "Outdoor lighting — 12 towers ROV01–ROV12 and the OŘ area",
            "Mode in force, lamps, faults, power; Manual/Auto and On/Off need remote enabled on the board.")
    for k, board in enumerate(LIGHTING):
        x = 20 + (k % cols) * (w + 8)
        y = 70 + (k // cols) * (h + 10)
        b = f"{board}_"
        svg.comment(f"Lighting board {board}")
        svg.open("g", id=f"board-{board}", transform=f"translate({x} {y})")
        svg.el("rect", x=0, y=0, width=w, height=h, rx=6, class_="box")
        svg.text(10, 20, board if board != "OR" else "OŘ area", "title")
        svg.el("circle", cx=w - 16, cy=14, r=6, class_="fault", data_point=use(f"COMM_{board}"))
        svg.text(w - 26, 18, "link", "label small", "end")
        svg.comment("lamp: lit while the lamp-circuit relay reports current; 'lighting ON' says so, the"
                    " command (Osv_Zap) is told apart")
        svg.el("circle", cx=30, cy=52, r=15, class_="lamp", data_point=use(f"{b}PrRele"))
        svg.text(54, 47, "", "value", data_text=use(f"{b}PrRele"), data_on="lighting ON",
                 data_off="lighting off")
        svg.text(54, 63, "", "label small", data_text=use(f"{b}Osv_Zap"), data_on="switched on",
                 data_off="switched off")
        svg.text(130, 63, "", "label small", data_text=use(f"{b}Zap_Rucne"), data_on="by hand", data_off="")
        svg.comment("mode in force, lit: LOCAL (cabinet), else MAN, else the automatic modes set (ASTRO,"
                    " DUSK, TIME); under MAN the automatic ones are set but not in force: drawn unlit")
        svg.text(10, 88, "MAN", "state small", data_text=use(f"{b}Osv_Rucne"), data_on="MAN", data_off="MAN")
        svg.open("g", class_="auto-modes", data_visible=use(f"{b}Osv_Rucne"), data_visible_when="off")
        for i, (flag, label) in enumerate([("Set_Astral", "ASTRO"), ("Set_Cidlo", "DUSK"), ("Set_Cas", "TIME")]):
            svg.text(54 + i * 44, 88, label, "state small", data_text=use(f"{b}{flag}"), data_on=label,
                     data_off=label)
        svg.close("g")
        svg.open("g", class_="auto-modes-held", data_visible=use(f"{b}Osv_Rucne"), data_visible_when="on")
        for i, label in enumerate(["ASTRO", "DUSK", "TIME"]):
            svg.text(54 + i * 44, 88, label, "state small")
        svg.close("g")
        svg.text(186, 88, "LOCAL", "state small", data_text=use(f"{b}Zap_Z_Rozvadece"), data_on="LOCAL",
                 data_off="LOCAL")
        svg.comment("contactor, faults")
        svg.el("rect", x=10, y=98, width=14, height=14, class_="breaker", data_point=use(f"{b}KM1_Zapnut"))
        svg.text(30, 110, "KM1", "label small")
        svg.el("circle", cx=80, cy=105, r=6, class_="fault", data_point=use(f"{b}Osv_Por"))
        svg.text(90, 109, "circuit fault", "label small")
        svg.el("circle", cx=170, cy=105, r=6, class_="fault", data_point=use(f"{b}Porucha_KM1"))
        svg.text(180, 109, "KM1 fault", "label small")
        svg.el("circle", cx=16, cy=126, r=5, class_="warn", data_point=use(f"{b}FU1_Pretavena_pojistka"))
        svg.text(25, 130, "fuse", "label small")
        svg.el("circle", cx=66, cy=126, r=5, class_="warn", data_point=use(f"{b}FV1_Prepetova_ochrana"))
        svg.text(75, 130, "surge", "label small")
        svg.el("circle", cx=122, cy=126, r=5, class_="warn", data_point=use(f"{b}Dvere"))
        svg.text(131, 130, "door", "label small")
        svg.el("circle", cx=172, cy=126, r=5, class_="ind", data_point=use(f"{b}Dalkove"))
        svg.text(181, 130, "remote", "label small")
        svg.comment("power and energy")
        svg.text(10, 152, "", "value", data_text=use(f"{b}P_kW"), data_unit="kW", data_digits="1")
        svg.text(70, 152, "", "value", data_text=use(f"{b}Energie_kWh"), data_unit="kWh", data_digits="1")
        svg.text(w - 10, 152, "apply times…", "value small", "end", data_command=use(f"{b}W_SetTime"),
                 data_command_value=1, data_label=f"{board}: take over the four window times")
        svg.comment("time windows: the dot is lit inside a window; W1/W2 on/off set the times (hh:mm setpoints,"
                    " which the board does not report back)")
        svg.open("g", class_="windows")
        svg.el("circle", cx=14, cy=163, r=5, class_="ind", data_point=use(f"{b}Zap_Cas"))
        svg.text(24, 167, "", "label small", data_text=use(f"{b}Zap_Cas"), data_on="inside a time window",
                 data_off="outside the time windows")
        for i, n in enumerate(["1", "2"]):
            for j, (which, word) in enumerate([("Zap", "on"), ("Vyp", "off")]):
                cmd = use(f"{b}W_Cas{n}{which}")
                svg.text(10 + (i * 2 + j) * 56, 182, f"W{n} {word}…", "value small", data_command=cmd,
                         data_command_format="minutes", data_label=f"{board}: time window {n}, {word} time")
        svg.close("g")
        svg.comment("manual controls")
        name = board if board != "OR" else "OŘ area"
        button(svg, 8, 190, 52, "Man", f"{b}W_Rucne", 1, f"{b}Osv_Rucne",
               words=f"Put the lighting of {name} in manual mode?")
        button(svg, 64, 190, 52, "Auto", f"{b}W_Rucne", 0, f"{b}Osv_Rucne",
               words=f"Put the lighting of {name} back in automatic mode?")
        button(svg, 120, 190, 50, "On", f"{b}W_ZapRucne", 1, f"{b}Osv_Zap",
               words=f"Switch the lighting of {name} on by hand?")
        button(svg, 174, 190, 50, "Off", f"{b}W_ZapRucne", 0, f"{b}Osv_Zap",
               words=f"Switch the lighting of {name} off by hand?")
        svg.close("g")
    svg.write("lighting.svg")


# ------------------------------------------------------------------------ topology
def topology():
    svg = Svg("Vsetín — controllers and links", 1200, 720)
    heading(svg, "Topology — controllers and IEC 104 links",
            "Green = link up, red dashed = link down or no client (COMM_* points of the TC700 and concentrators).")

    svg.comment("Upper systems served by RDRT (spec 7.5): ED, MŘS and the service access have their"
                " link points (SP 38, 39, 41: TRUE while no client of theirs is connected); DDTS and"
                " DŘT share the dispatch group and its link point (SP 42)")
    svg.open("g", id="upper")
    for i, (name, comm) in enumerate([("DDTS", "COMM_DISPATCH"), ("DŘT", "COMM_DISPATCH"), ("ED", "COMM_ED"),
                                      ("MŘS", "COMM_MRS"), ("Servis", "COMM_SERVIS")]):
        x = 300 + i * 130
        if comm:
            svg.el("path", d=f"M {x + 50} 109 V 150", class_="comm", data_point=use(comm))
            svg.el("rect", x=x, y=75, width=100, height=34, rx=5, class_="comm-node", data_point=comm)
        else:
            svg.el("path", d=f"M {x + 50} 109 V 150", class_="wire")
            svg.el("rect", x=x, y=75, width=100, height=34, rx=5, class_="frame")
        svg.text(x + 50, 91 if comm else 97, name, "label", "middle")
        if comm:
            svg.text(x + 50, 104, "", "label small", "middle", data_text=comm, data_on="link down",
                     data_off="link up")
    svg.el("path", d="M 350 150 H 870", class_="wire")
    svg.el("path", d="M 600 150 V 170", class_="wire")
    svg.close("g")

    svg.comment("This HMI's own link to RDRT")
    svg.open("g", id="hmi")
    svg.el("rect", x=60, y=160, width=150, height=50, rx=6, class_="comm-node", data_link_status="")
    svg.text(75, 182, "Web HMI", "title")
    svg.text(75, 200, "", "label small", data_link_status="")
    svg.el("path", d="M 210 185 H 520", class_="comm", data_link_status="")
    svg.close("g")

    svg.comment("RDRT: Tecomat TC700, the top controller")
    svg.open("g", id="RDRT")
    svg.el("rect", x=520, y=170, width=160, height=60, rx=6, class_="box")
    svg.text(535, 193, "RDRT", "title")
    svg.text(535, 212, "Tecomat TC700", "label small")
    svg.close("g")

    def node(x, y, name, subtitle, comm, link_path, screen=None):
        svg.comment(f"{name}: link status {comm} (TRUE = failure)")
        svg.open("g", id=f"node-{name}")
        svg.el("path", d=link_path, class_="comm", data_point=use(comm))
        svg.el("rect", x=x, y=y, width=140, height=50, rx=6, class_="comm-node", data_point=comm)
        if screen:
            svg.open("a", href=f"#screen/{screen}")
            svg.text(x + 10, y + 21, f"{name} ›", "title")
            svg.close("a")
        else:
            svg.text(x + 10, y + 21, name, "title")
        svg.text(x + 10, y + 39, subtitle, "label small")
        svg.close("g")

    node(300, 300, "RH1.1", "S7-1500 (TO)", "COMM_RH", "M 560 230 V 265 H 370 V 300", "rh11")
    node(450, 300, "RH in DT", "S7-1500 (DT)", "COMM_RH_DT", "M 580 230 V 282 H 520 V 300", "dt")
    node(760, 300, "RZS1", "S7-1500 (TO)", "COMM_RZS", "M 640 230 V 265 H 830 V 300", "rzs1")
    node(910, 300, "RZS in DT", "S7-1500 (DT)", "COMM_RZS_DT", "M 620 230 V 282 H 980 V 300", "dt")
    node(290, 410, "RH2", "LOGO!", "COMM_RH2", "M 360 350 V 410", "rh2")
    node(440, 410, "RH1.2", "LOGO!", "COMM_RH12", "M 380 350 V 385 H 510 V 410", "rh12")
    node(610, 410, "RZZ", "LOGO!", "COMM_RZZ", "M 810 350 V 385 H 680 V 410", "rzz")
    node(760, 410, "RDA", "LOGO!", "COMM_RDA", "M 830 350 V 410", "rda")
    node(910, 410, "RZS2", "LOGO!", "COMM_RZS2", "M 850 350 V 385 H 980 V 410", "rzs2")

    svg.comment("The thirteen lighting boards, each on its own link from RDRT")
    svg.open("g", id="lighting-links")
    svg.el("path", d="M 600 230 V 250 H 1130 V 530", class_="wire")
    svg.text(1000, 245, "optical network (lighting)", "label small")
    for k, board in enumerate(LIGHTING):
        x = 22 + k * 90
        svg.el("path", d=f"M {x + 40} 530 V 560", class_="comm", data_point=use(f"COMM_{board}"))
        svg.el("rect", x=x, y=560, width=80, height=44, rx=5, class_="comm-node", data_point=f"COMM_{board}")
        svg.open("a", href="#screen/lighting")
        svg.text(x + 40, 580, board if board != "OR" else "OŘ", "title", "middle", font_size=14)
        svg.close("a")
        svg.text(x + 40, 596, "S7-1500" if board == "OR" else "S7-1200", "label small", "middle")
    svg.el("path", d=f"M 62 530 H {22 + 12 * 90 + 40} ", class_="wire")
    svg.close("g")

    svg.comment("RDRT's own diagnostics (spec 7.3): supplies, surge arresters, switches, modules, doors")
    svg.open("g", id="rdrt-diagnostics")
    svg.el("rect", x=20, y=250, width=250, height=270, rx=6, class_="frame")
    svg.text(32, 272, "RDRT diagnostics", "title")
    rows = [
        ("RDRT_SP4_G230", "supply G230 fault", "fault"),
        ("RDRT_SP5_G110", "supply G110 fault", "fault"),
        ("RDRT_SP6_G24", "supply G24 fault", "fault"),
        ("RDRT_SP1_FV230", "surge arrester FV230", "warn"),
        ("RDRT_SP2_FV110", "surge arrester FV110", "warn"),
        ("RDRT_SP3_FV24", "surge arrester FV24", "warn"),
        ("RDRT_SP8_Korenix", "Korenix switch fault", "fault"),
        ("RDRT_SP9_ABB", "ABB switch fault", "fault"),
        ("RDRT_SP10_Siemens", "Siemens switch fault", "fault"),
        ("RDRT_SP24_PoruchaModul6", "module P6 fault", "fault"),
        ("RDRT_SP25_PoruchaModul9", "module P9 fault", "fault"),
    ]
    for i, (point, label, cls) in enumerate(rows):
        indicator(svg, 40, 292 + i * 20, point, label, cls, 6)
    svg.close("g")
    svg.open("g", id="doors")
    svg.el("rect", x=960, y=640, width=220, height=70, rx=6, class_="frame")
    svg.text(972, 658, "Switchroom doors", "label")
    for i, (point, label) in enumerate([("RDRT_SP26_Dvere_NN", "LV"), ("RDRT_SP27_Dvere_VN", "HV"),
                                        ("RDRT_SP28_Dvere_T1", "T1"), ("RDRT_SP29_Dvere_T2", "T2")]):
        indicator(svg, 980 + i * 50, 686, point, label, "warn", 6)
    svg.close("g")
    svg.write("topology.svg")


# ------------------------------------------------------------------------ hmi.toml
HMI_TOML_HEAD = """\
# The Vsetín web HMI (docs/HMI.md): screens, controls, alarms and trends.
# Written by generate_screens.py together with the SVG files.
# Levels (elevator spec 10): 0 read-only, 3 lighting, 5 power boards,
# 7 control authority, 9 administrator.

title = "Vsetín railway station"
# The address the HMI connects to RDRT from: the station's redundancy group "hmi" (the
# TC700's local HMI, with command authority) takes clients from 127.0.0.2; from another
# address the HMI would be dispatch, whose commands the station refuses while it is local.
local_address = "127.0.0.2"
# The zone the station stamps its time tags in (its station.toml's time_zone).
time_zone = "Europe/Prague"
# Printed by the station's banner beside the users file (users.toml holds only hashes).
sign_in_note = "the demo's are operator / operator-vsetin, admin / admin-vsetin, viewer / viewer-vsetin"
default_control_level = 5
"""

SCREENS = [("supply", "Supply", "supply.svg"), ("topology", "Topology", "topology.svg"),
           ("rh11", "RH1.1 / R6", "rh11.svg"), ("rh2", "RH2", "rh2.svg"), ("rh12", "RH1.2", "rh12.svg"),
           ("rzs1", "RZS1 / signalling", "rzs1.svg"), ("rzz", "RZZ", "rzz.svg"), ("rzs2", "RZS2", "rzs2.svg"),
           ("rda", "RZS / RDA", "rda.svg"), ("dt", "DT", "dt.svg"), ("lighting", "Lighting", "lighting.svg")]
# LOGO! boards with a feeder breaker QF1 under control: (plant prefix, name in the thesis)
QF1_BOARDS = [("RH2", "RH2"), ("RZZ", "RZZ"), ("RH12", "RH1.2"), ("RZS2", "RZS2")]


def toml_value(value):
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {toml_value(v)}" for k, v in value.items()) + " }"
    return '"' + str(value).replace("\\", "\\\\").replace('"', '\\"') + '"'


def toml_table(name, **fields):
    lines = [f"[[{name}]]"]
    for key, value in fields.items():
        if value is not None:
            lines.append(f"{key} = {toml_value(value)}")
    return "\n".join(lines) + "\n"


# The link point (COMM_*, TRUE while the link is lost) each board's points come through:
# an alarm behind a lost link is a consequence of the link's alarm, not raised on its own
# (docs/HMI.md, "Alarm management"). RH2 and RH1.2 are reached through RH1.1, RZZ, RDA and
# RZS2 through RZS1, so their link alarms are consequences of those links in turn.
ALARM_LINKS = {"RH2": "COMM_RH2", "RZZ": "COMM_RZZ", "RH12": "COMM_RH12", "RZS2": "COMM_RZS2",
               "RDA": "COMM_RDA", "RH11": "COMM_RH", "RZS1": "COMM_RZS", "RHDT": "COMM_RH_DT",
               "RZSDT": "COMM_RZS_DT", **{b: f"COMM_{b}" for b in LIGHTING}}
LINK_BEHIND = {"COMM_RH2": "COMM_RH", "COMM_RH12": "COMM_RH", "COMM_RZZ": "COMM_RZS",
               "COMM_RDA": "COMM_RZS", "COMM_RZS2": "COMM_RZS"}


def alarm_link(point):
    """The link point an alarm's point comes through, or None (RDRT's own points)."""
    if point in LINK_BEHIND:
        return LINK_BEHIND[point]
    if point.startswith("COMM_"):
        return None
    return ALARM_LINKS.get(point.split("_")[0])


def alarm_suppression(point):
    """Suppression by design. A lighting board's lighting-circuit fault is suppressed while
    the board is under local (cabinet) control: the maintainer at the cabinet switches
    circuits by hand and opens them to work on them, which the fault input reports, and
    nobody in dispatch can act on it meanwhile. Not the fuse, surge-arrester or KM1 alarms:
    a blown fuse or a failed contactor under local control is still a fault to repair.
    (Nor a board's fuses while its QF1 is open: QF1 opens on such faults, so that would
    hide the cause of the trip.)"""
    board = point.split("_")[0]
    if board in LIGHTING and point == f"{board}_Osv_Por":
        return {"point": use(f"{board}_Zap_Z_Rozvadece"), "state": True}
    return None


def alarm_list():
    alarms = [
        ("RDA_Porucha", 1, "RDA: transfer fault"),
        ("RDA_BezNapeti", 1, "RZS without supply"),
        ("RDA_HavarijniVyp", 1, "RDA: emergency off"),
        ("RH2_P1_KHVRH2_Havarijni_vypnuti", 1, "RH2: emergency off"),
        ("RZZ_P1_KHVRZZ_Havarijni_vypnuti", 1, "RZZ: emergency off"),
        ("RH12_P1_KHVRH12_Havarijni_vypnuti", 1, "RH1.2: emergency off"),
        ("RZS2_P1_KHVRZS2_Havarijni_vypnuti", 1, "RZS2: emergency off"),
        ("UZ_K2_Zapnut", 2, "Signalling equipment on its backup supply (RZS1)"),
        ("RDA_Porucha_DA", 2, "RDA: generator fault"),
        ("RDA_DA_Porucha", 2, "RDA: generator failed to start"),
        ("RDA_Porucha_KM1", 2, "RDA: contactor KM1 does not follow its coil"),
        ("RDA_Porucha_KM2", 2, "RDA: contactor KM2 does not follow its coil"),
        ("RDRT_SP4_G230", 2, "RDRT: power supply G230 fault"),
        ("RDRT_SP5_G110", 2, "RDRT: supply G110 fault"),
        ("RDRT_SP6_G24", 2, "RDRT: supply G24 fault"),
        ("RDRT_SP24_PoruchaModul6", 2, "RDRT: module P6 fault"),
        ("RDRT_SP25_PoruchaModul9", 2, "RDRT: module P9 fault"),
        ("COMM_RH", 2, "Link RDRT - RH1.1 failed"),
        ("COMM_RZS", 2, "Link RDRT - RZS1 failed"),
        ("COMM_RH2", 2, "Link RH1.1 - RH2 failed"),
        ("COMM_RZZ", 2, "Link RZS1 - RZZ failed"),
        ("COMM_RDA", 2, "Link RZS1 - RDA failed"),
        ("COMM_RH12", 2, "Link RH1.1 - RH1.2 failed"),
        ("COMM_RZS2", 2, "Link RZS1 - RZS2 failed"),
        ("COMM_RH_DT", 2, "Link RDRT - RH in DT failed"),
        ("COMM_RZS_DT", 2, "Link RDRT - RZS in DT failed"),
    ]
    # Raised while FALSE: (point, priority, text)
    alarms_when_off = [("UZ_Vystup", 1, "Signalling equipment without supply"),
                       ("RHDT_KHU1_Napeti", 2, "RH in DT without voltage")]
    alarms += [(f"COMM_{b}", 2, f"Link RDRT - lighting board {b} failed") for b in LIGHTING]
    alarms += [(f"{b}_Osv_Por", 3, f"{b}: lighting-circuit fault") for b in LIGHTING]
    alarms += [(f"{b}_Porucha_KM1", 3, f"{b}: lighting contactor KM1 fault") for b in LIGHTING]
    for board, name in QF1_BOARDS:
        alarms += [(f"{board}_P1_FU1_Pretavena_pojistka", 3, f"{name}: fuse FU1 blown"),
                   (f"{board}_P1_FV1_Prepetova_ochrana", 3, f"{name}: surge arrester FV1 tripped"),
                   (f"{board}_P1_FV110_Prepetova_ochrana", 3, f"{name}: surge arrester FV110 tripped")]
    for board, name in [("RH11", "RH1.1"), ("RZS1", "RZS1"), ("RHDT", "RH in DT"), ("RZSDT", "RZS in DT")]:
        alarms += [(f"{board}_FU1_Pretavena_pojistka", 3, f"{name}: fuse FU1 blown"),
                   (f"{board}_FV1_Prepetova_ochrana", 3, f"{name}: surge arrester FV1 tripped")]
    alarms += [("RDA_FU1_PretavenaPojistka", 3, "RDA: fuse FU1 blown"),
               ("RDA_FV1_PrepetovaOchrana", 3, "RDA: surge arrester FV1 tripped"),
               ("RDRT_SP1_FV230", 3, "RDRT: surge arrester FV230 tripped"),
               ("RDRT_SP2_FV110", 3, "RDRT: surge arrester FV110 tripped"),
               ("RDRT_SP3_FV24", 3, "RDRT: surge arrester FV24 tripped"),
               ("RDRT_SP8_Korenix", 3, "RDRT: Korenix switch fault"),
               ("RDRT_SP9_ABB", 3, "RDRT: ABB switch fault"),
               ("RDRT_SP10_Siemens", 3, "RDRT: Siemens switch fault")]
    for b in LIGHTING:
        alarms += [(f"{b}_FU1_Pretavena_pojistka", 3, f"{b}: lamp-circuit fuse blown"),
                   (f"{b}_FV1_Prepetova_ochrana", 3, f"{b}: surge arrester tripped")]
    alarms += [("RDRT_SP26_Dvere_NN", 4, "LV switchroom door open"),
               ("RDRT_SP27_Dvere_VN", 4, "HV switchroom door open"),
               ("RDRT_SP28_Dvere_T1", 4, "Transformer chamber T1 door open"),
               ("RDRT_SP29_Dvere_T2", 4, "Transformer chamber T2 door open"),
               ("RS602_Zapnut", 4, "6 kV switchroom R6 by-passed (RS602 closed)")]
    return [(point, priority, text, True) for point, priority, text in alarms] + \
        [(point, priority, text, False) for point, priority, text in alarms_when_off]


def hmi_toml():
    out = [HMI_TOML_HEAD]
    for sid, title, file in SCREENS:
        out.append(toml_table("screen", id=sid, title=title, file=file))

    out.append("# ---------------------------------------------------------------- controls\n"
               "# The control authority (spec 7.4): the station takes it only from this HMI's link.\n"
               "# It needs no authority itself: it is how this HMI takes the authority back.")
    out.append(toml_table("control", command=use("RDRT_HMI_Mistne"), level=7,
                          confirm="Change the control authority between this HMI (local) and the remote dispatch?"))
    out.append("# The board views' functional elements (QF1 of the LOGO! boards, the RDA test run) work only\n"
               "# while the control authority is with this HMI (spec 9.2): SP 21 \"HMI local\" TRUE.\n"
               "# The HMI refuses them itself otherwise (refused-authority) and audits the refusal.")
    # The station itself gates only the dispatch (ED) link by SP 21 (spec 7.5), not the HMI's.
    authority = {"point": use("RDRT_SP21_HMI_Mistne"), "state": True}
    for board, name in QF1_BOARDS:
        out.append(f"# {name}: feeder breaker QF1 (spec 5.1, 5.2), select-before-operate; refused with SA1 in local.")
        for cmd, verb in [("VypnoutQF1", "Open"), ("ZapnoutQF1", "Close")]:
            out.append(toml_table("control", command=use(f"{board}_{cmd}"), level=5, select=True,
                                  confirm=f"{verb} feeder breaker QF1 of {name}?",
                                  local_point=use(f"{board}_P1_SA1_Mistne"), authority=authority))
    out.append(toml_table("control", command=use("RDA_ProvozDA"), level=5,
                          confirm="Test run: supply RZS from the diesel generator (or end the test run)?",
                          local_point=use("RDA_SA1_Mistne"), authority=authority))
    out.append("# Lighting boards: level 3; refused while the board is under local (cabinet) control.\n"
               "# No authority: their settings are the dispatch's own inputs (spec 4.2, \"in (DDTS)\"),\n"
               "# and spec 9.2 restricts only the board views' breakers to HMI-local authority.")
    for board in LIGHTING:
        # W_Rucne and W_ZapRucne mean two things (on/off): the buttons' words ask the question.
        for cmd, confirm in [("W_Rucne", None), ("W_ZapRucne", None),
                             ("W_Astral", None), ("W_Cidlo", None), ("W_Cas", None), ("W_SetTime", None),
                             ("W_Cas1Zap", None), ("W_Cas1Vyp", None), ("W_Cas2Zap", None), ("W_Cas2Vyp", None)]:
            out.append(toml_table("control", command=use(f"{board}_{cmd}"), level=3, confirm=confirm,
                                  local_point=use(f"{board}_Zap_Z_Rozvadece")))

    out.append("# ---------------------------------------------------------------- alarms\n"
               "# 1 supply lost / emergency off, 2 generator, controller and link faults,\n"
               "# 3 lighting circuits, fuses and surge arresters, 4 doors.")
    for point, priority, text, when in alarm_list():
        link = alarm_link(point)
        out.append(toml_table("alarm", point=use(point), priority=priority, text=text,
                              when=None if when else False, acknowledge=priority <= 3,
                              suppress_when=alarm_suppression(point),
                              link=use(link) if link else None))

    out.append("# ---------------------------------------------------------------- trends")
    for b in LIGHTING:
        out.append(toml_table("trend", point=use(f"{b}_P_kW")))
        out.append(toml_table("trend", point=use(f"{b}_Energie_kWh")))
    out.append(toml_table("trend", point=use("RDA_Stav")))
    for board in [b for b, _ in QF1_BOARDS] + ["RH11", "RZS1", "RHDT", "RZSDT"]:
        for meter in ["U", "P_kW", "I_A", "Energie_kWh"]:
            out.append(toml_table("trend", point=use(f"{board}_{meter}")))
    for point in ["R6_U", "R6_T_U", "SZZ_P_kW"]:
        out.append(toml_table("trend", point=use(point)))
    (HERE / "hmi.toml").write_text("\n".join(out), encoding="utf-8")
    print("wrote hmi.toml")


if __name__ == "__main__":
    hmi_toml()
    supply()
    topology()
    rh11()
    power_board("RH2", "transformer T2", "RH1.1", "COMM_RH",
                feeders=["ROV01–03", "ROV04–06", "ROV07–09", "ROV10–12", "OŘ"])
    power_board("RH12", "RH1.1", "RH1.1", "COMM_RH", name="RH1.2")
    rzs1()
    power_board("RZZ", "transformer T1 (TZ1)", "RZS1", "COMM_RZS")
    power_board("RZS2", "RZS (secured network)", "RZS1", "COMM_RZS")
    rda()
    dt()
    lighting()
    print(f"{len(USED)} points and commands bound")
