#!/usr/bin/env python3
"""Writes examples/vsetin/station.toml, the Vsetín railway station project, and with
`--s7` its variant examples/vsetin-s7 (station.toml and the concentrators' programs), in
which the LOGO! boards report to the S7-1500 concentrators over S7 connections as in the
thesis (section 3.3) instead of IEC 104.

The project is plain TOML and runs as it is; this script only saves typing the thirteen
lighting boards and the repeated board points. Edit the tables below and run

    python3 examples/vsetin/tools/generate_station_toml.py
    python3 examples/vsetin/tools/generate_station_toml.py --s7

IOA plan (the railway-station thesis's point lists, docs/THESES.md; where it is silent, ours):
  RDRT own points      1-10 SP of module P9, 21 HMI local, 24/25 module faults,
                       26-29 switchroom doors, 32/33 links RH/RZS (TO), 34/35 links RH/RZS
                       in DT, 38-41 upper links ED/MŘS/HMI/service, 42 the dispatch
                       link (DDTS/DŘT), 50-62 links
                       ROV01..OR; command 2001 HMI local
  RH1.1 own I/O        201-208 SP (QF1, KHU1, FV1, FU1, R6 cubicles Q1-Q3, by-pass
                       RS602), 211-216 ME (meter, R6 and transformer 6 kV voltages)
  RH2 (via RH1.1)      281-298 (thesis), commands 2021/2022 (thesis), meter 271-274;
                       RH1.1's link 280
  RH1.2 (via RH1.1)    RH2's + 40: 321-338, meter 311-314, commands 2061/2062; link 320
  RZS1 own I/O         341-348 SP (KHU1, FV1, FU1, the universal source of the signalling
                       equipment), 351-355 ME (meter, signalling load)
  RZZ (via RZS1)       381-398 (RZZ's own 281-298 + 100), meter 371-374, commands
                       2121/2122
  RDA (via RZS1)       401-421, command 2201; RZS1's links: 380 RZZ, 400 RDA
  RZS2 (via RZS1)      RZZ's + 60: 441-458, meter 431-434, commands 2181/2182; link 440
  RH in DT             501-504 SP, 511-514 ME;   RZS in DT   601-604 SP, 611-614 ME
  lighting board k     10000 + 100*k + n (ROV01 = 1, ..., ROV12 = 12, OR = 13):
                       points n = 1-22 and 31/32, commands n = 51-64
                       (no IOA is both a point and a command: many controlling
                       stations keep one object per address)
Ports: port_base + 0 RDRT, 1 RH1.1, 2 RH2, 3 RZS1, 4 RZZ, 5 RDA, 6 RH1.2, 7 RZS2, 8 RH in DT,
9 RZS in DT, 9 + k lighting board k.
"""

import sys
from pathlib import Path

S7 = "--s7" in sys.argv[1:]
HERE = Path(__file__).resolve().parent.parent
OUT = (HERE.parent / "vsetin-s7" if S7 else HERE) / "station.toml"
# The variant shares the programs and the calendar of examples/vsetin.
SHARED = "../vsetin/" if S7 else ""
LIGHTING = [f"ROV{k:02d}" for k in range(1, 13)] + ["OR"]

out = []


def emit(text=""):
    out.append(text)


def table(header, **fields):
    emit(f"[{header}]" if not header.startswith("[") else header)
    for key, value in fields.items():
        emit(f"{key} = {toml(value)}")
    emit()


def toml(value):
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return str(value)
    if isinstance(value, list):
        return "[" + ", ".join(toml(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {toml(v)}" for k, v in value.items()) + " }"
    return '"' + str(value).replace("\\", "\\\\").replace('"', '\\"') + '"'


def node(name, description, ca, port_offset=None, sources=None, allowed=True, groups=None):
    emit("# " + "-" * 87)
    table("[[node]]", name=name, description=description, common_address=ca,
          **({"sources": sources} if sources else {}))
    if port_offset is not None:
        server = {"port_offset": port_offset}
        if allowed:
            server["allowed_clients"] = ["127.0.0.1"]
        if groups:
            server["redundancy_groups"] = groups
        table("node.server", **server)


def task(name, interval_ms, programs, watchdog_ms):
    table("[[node.task]]", name=name, interval_ms=interval_ms, priority=1,
          programs=programs, watchdog_ms=watchdog_ms)


def io(signal, variable):
    table("[[node.io]]", signal=signal, variable=variable)


def point(name, type_id, ioa, source=None, description="", **extra):
    fields = {"name": name, "type": type_id, "ioa": ioa}
    if source:
        fields["source"] = source
    fields.update(extra)
    fields["description"] = description
    table("[[node.point]]", **fields)


def command(name, type_id, ioa, target, description, **extra):
    table("[[node.command]]", name=name, type=type_id, ioa=ioa, target=target, **extra,
          description=description)


def link(name, target, status_point=None, republish=None):
    fields = {"name": name, "node": target}
    if status_point:
        fields["status_point"] = status_point
    if republish is not None:
        fields["republish"] = {"ioa_offset": republish}
    table("[[node.link]]", **fields)


emit("" if S7 else """# The Vsetín railway station (the railway-station thesis, docs/THESES.md): power boards RH2, RZZ,
# RDA, RH1.2 and RZS2 (LOGO!), the concentrators RH1.1 and RZS1 in TO and RH and RZS in DT
# (S7-1500), twelve lighting-tower boards ROV01..ROV12 (S7-1200) and the OŘ-area lighting
# (S7-1500 in DT), and the central PLC RDRT (Tecomat TC700) serving the dispatch systems.
# Every node is an IEC 104 server; each upper node concentrates the ones below over IEC
# 104 links on loopback. The choices made where the thesis is silent are listed in
# README.md.
#
# Written by tools/generate_station_toml.py (its header has the IOA and port plan); the
# format is documented in crates/station/src/config/mod.rs.
""")
if S7:
    emit("""# The Vsetín railway station with its LOGO! boards on S7 connections (the railway-station
# thesis, docs/THESES.md, section 3.3): RH1.1 and RZS1 serve their PLC memory over S7
# ([node.s7_server]) as the S7-1500 concentrators do, and the boards RH2, RH1.2, RZZ, RZS2
# and RDA are simulated LOGO!s that connect to them as S7 clients, writing their inputs
# into the concentrators' markers (tag list 6.1) and reading their commands from them.
# Everything else is examples/vsetin, whose programs and calendar this project uses.
# Against real LOGO!s: drop the five board nodes and let the concentrators listen on 102.
#
#   stanice run examples/vsetin-s7
""")
table("station", name="Vsetín (S7)" if S7 else "Vsetín", time_zone="Europe/Prague",
      store="sqlite:events.sqlite", retention_days=60, port_base=2504 if S7 else 2404,
      bind="127.0.0.1", plant="vsetin")

# --------------------------------------------------------------------------------------
# Power boards RH2 and RZZ: the LOGO! QF1 logic (spec 5.1, 5.2).
BOARD_INPUTS = [
    # (plant signal suffix, variable, point suffix for names, description)
    ("V1_FA1_Zapnut", "FA1_Zapnut", "breaker FA1 closed"),
    ("V1_FA1.1", "FA1_1", "breaker FA1.1 closed"),
    ("V1_FA1.2", "FA1_2", "breaker FA1.2 closed"),
    ("V1_FA1.3", "FA1_3", "breaker FA1.3 closed"),
    ("V1_FA1.4", "FA1_4", "breaker FA1.4 closed"),
    ("V1_FA1.5", "FA1_5", "breaker FA1.5 closed"),
    ("P1_FA110.0", "FA110_0", "breaker FA110.0 (110 V circuit) closed"),
    ("P1_FA110.1", "FA110_1", "breaker FA110.1 closed"),
    ("P1_FA110.2", "FA110_2", "breaker FA110.2 closed"),
    ("P1_KHU1_Napeti_na_privodu", "KHU1_NapetiNaPrivodu", "voltage present on incoming feeder (relay KHU1)"),
    ("P1_KHU3_Napeti_na_pripojeni", "KHU3_NapetiNaPripojeni", "voltage present on connection (relay KHU3)"),
    ("P1_SA1_Mistne", "SA1_Mistne", "selector SA1 in local"),
    ("P1_SA1_Dalkove", "SA1_Dalkove", "selector SA1 in remote"),
    ("P1_FU1_Pretavena_pojistka", "FU1_PretavenaPojistka", "fuse FU1 blown"),
    ("P1_FV1_Prepetova_ochrana", "FV1_PrepetovaOchrana", "surge protection FV1 tripped"),
    ("P1_KHV{B}_Havarijni_vypnuti", "HavarijniVyp", "emergency off of {B}"),
    ("P1_FV110_Prepetova_ochrana", "FV110_PrepetovaOchrana", "surge protection FV110 (110 V) tripped"),
    ("P1_G110.2_Napeti_zdroje", "G110_2_NapetiZdroje", "voltage of source G110.2"),
]


LOGO = "LogoBoard"
LOGO_SOURCE = "plc/logo_board.st"


def power_board(name, board, ca, port_offset, description):
    """A LOGO! board node `name` on the plant signals `board`_* (RH1.2's are RH12_*)."""
    program = LOGO
    node(name, description, ca, port_offset, sources=[f"{SHARED}{LOGO_SOURCE}"])
    task("main", 10, [program], 100)  # a LOGO! scans in milliseconds
    for suffix, variable, _ in BOARD_INPUTS:
        io(f"{board}_{suffix.replace('{B}', board)}", f"{program}.{variable}")
    io(f"{board}_QF1_Zapnut", f"{program}.QF1_Zapnut")
    for meter in ["U", "P_kW", "I_A", "Energie_kWh"]:
        io(f"{board}_{meter}", f"{program}.{meter}")
    io(f"{board}_QF1_Vyp", f"{program}.QF1_OFF")
    io(f"{board}_QF1_Zap", f"{program}.QF1_ON")
    for i, (suffix, variable, text) in enumerate(BOARD_INPUTS):
        suffix = suffix.replace("{B}", board)
        point(f"{board}_{suffix}", "M_SP_TB_1", 281 + i, f"{program}.{variable}",
              text.replace("{B}", name))
    # The board's meter (not in the thesis' point list; ours): float with deadband.
    for ioa, meter, text, deadband in [(271, "U", "busbar voltage, V", 5.0),
                                       (272, "P_kW", "load power, kW", 0.5),
                                       (273, "I_A", "phase current, A", 1.0),
                                       (274, "Energie_kWh", "energy meter, kWh", 1.0)]:
        point(f"{board}_{meter}", "M_ME_TF_1", ioa, f"{program}.{meter}", text, deadband=deadband)
    command(f"{board}_VypnoutQF1", "C_SC_NA_1", 2021, f"{program}.Cmd_VypnoutQF1", "open QF1",
            remote_enable=f"{program}.SA1_Dalkove", pulse_ms=500)
    command(f"{board}_ZapnoutQF1", "C_SC_NA_1", 2022, f"{program}.Cmd_ZapnoutQF1", "close QF1",
            remote_enable=f"{program}.SA1_Dalkove", pulse_ms=500)


# --------------------------------------------------------------------------------------
# The S7-1500 concentrators' own I/O (their DI modules; not in the thesis's point lists,
# ours): (plant signal = point name, IOA, description); REAL signals are measurements
# with the deadband given.
OWN_IO = {
    "RH1.1": ("RH11Concentrator", "RH11_DI", [
        ("RH11_QF1_Zapnut", 201, "main breaker QF1 (utility feed) closed"),
        ("RH11_KHU1_Napeti_sit", 202, "utility voltage present (relay KHU1)"),
        ("RH11_FV1_Prepetova_ochrana", 203, "surge arrester FV1 tripped"),
        ("RH11_FU1_Pretavena_pojistka", 204, "fuse FU1 blown"),
        ("R6_Q1_Zapnut", 205, "R6 incoming cubicle Q1 (line from TNS Ústí) closed"),
        ("R6_Q2_Zapnut", 206, "R6 incoming cubicle Q2 (line from TNS Valašské Meziříčí) closed"),
        ("R6_Q3_Zapnut", 207, "R6 transformer feeder Q3 closed"),
        ("RS602_Zapnut", 208, "6 kV by-pass disconnector box RS602 closed (R6 by-passed)"),
    ], [
        ("RH11_U", 211, "busbar voltage, V", 5.0),
        ("RH11_P_kW", 212, "load power, kW", 0.5),
        ("RH11_I_A", 213, "phase current, A", 1.0),
        ("RH11_Energie_kWh", 214, "energy meter, kWh", 1.0),
        ("R6_U", 215, "6 kV switchroom R6 voltage, V", 50.0),
        ("R6_T_U", 216, "6 kV voltage at the transformers T1/T2, V", 50.0),
    ]),
    "RZS1": ("RZS1Concentrator", "RZS1_DI", [
        ("RZS1_KHU1_Napeti", 341, "RZS busbar voltage present (relay KHU1)"),
        ("RZS1_FV1_Prepetova_ochrana", 342, "surge arrester FV1 tripped"),
        ("RZS1_FU1_Pretavena_pojistka", 343, "fuse FU1 blown"),
        ("UZ_Napeti_RZZ", 344, "signalling supply: input from RZZ (TZ1) live"),
        ("UZ_Napeti_RZS1", 345, "signalling supply: backup input from RZS1 live"),
        ("UZ_K1_Zapnut", 346, "signalling equipment fed from RZZ (TZ1)"),
        ("UZ_K2_Zapnut", 347, "signalling equipment fed from RZS1 (backup)"),
        ("UZ_Vystup", 348, "signalling equipment supplied"),
    ], [
        ("RZS1_U", 351, "busbar voltage, V", 5.0),
        ("RZS1_P_kW", 352, "load power, kW", 0.5),
        ("RZS1_I_A", 353, "phase current, A", 1.0),
        ("RZS1_Energie_kWh", 354, "energy meter, kWh", 1.0),
        ("SZZ_P_kW", 355, "power of the signalling equipment, kW", 0.5),
    ]),
}
for dt_node, board, base, feed in [("RH-DT", "RHDT", 500, "RH1.1"), ("RZS-DT", "RZSDT", 600, "RZS")]:
    OWN_IO[dt_node] = (f"{board}Concentrator", f"{board}_DI", [
        (f"{board}_QF1_Zapnut", base + 1, f"incoming breaker QF1 (cable from {feed}) closed"),
        (f"{board}_KHU1_Napeti", base + 2, "busbar voltage present (relay KHU1)"),
        (f"{board}_FV1_Prepetova_ochrana", base + 3, "surge arrester FV1 tripped"),
        (f"{board}_FU1_Pretavena_pojistka", base + 4, "fuse FU1 blown"),
    ], [
        (f"{board}_U", base + 11, "busbar voltage, V", 5.0),
        (f"{board}_P_kW", base + 12, "load power, kW", 0.5),
        (f"{board}_I_A", base + 13, "phase current, A", 1.0),
        (f"{board}_Energie_kWh", base + 14, "energy meter, kWh", 1.0),
    ])
PROGRAMS = {}  # concentrator program -> [(tag, address, type, comment)], written as tag tables


def own_io(name):
    """The concentrator `name`'s own inputs: plant signals into its tag table, its points
    invalid while its DI module is pulled or unreachable."""
    program, module, bools, reals = OWN_IO[name]
    tags = PROGRAMS.setdefault(program, [])
    tags.append(("PoruchaDI", None, "BOOL", f"DI module {module} pulled or unreachable"))
    io(f"module-fault:{module}", f"{program}.PoruchaDI")
    for signal, ioa, text in bools:
        tags.append((signal, None, "BOOL", text))
        io(signal, f"{program}.{signal}")
        point(signal, "M_SP_TB_1", ioa, f"{program}.{signal}", text,
              invalid_when=f"{program}.PoruchaDI")
    for signal, ioa, text, deadband in reals:
        tags.append((signal, None, "REAL", text))
        io(signal, f"{program}.{signal}")
        point(signal, "M_ME_TF_1", ioa, f"{program}.{signal}", text, deadband=deadband,
              invalid_when=f"{program}.PoruchaDI")


SHARED_PROGRAMS = set()  # tag tables the S7 variant takes from examples/vsetin


def concentrator_node(name, description, ca, port_offset, shared=False):
    """A concentrator with its own I/O; `shared`: the same in both projects (the S7
    variant uses examples/vsetin's tag table)."""
    program = OWN_IO[name][0]
    folder = SHARED if shared else ""
    if shared:
        SHARED_PROGRAMS.add(program)
    node(name, description, ca, port_offset, sources=[f"{folder}plc/{program.lower()}.st"])
    task("main", 10, [program], 100)
    own_io(name)
    return program


# --------------------------------------------------------------------------------------
# The TC700's upper links (spec 7.5) as redundancy groups chosen by client address: the
# local HMI panel, ED (electric dispatch, with service), MŘS, the service access, and every
# other client as the dispatch systems DDTS/DŘT. While HMI-local mode is on, commands from
# all but the HMI are refused (AllowCmd, 7.5). Each link's failure is a point (7.3).
BLOCKED = "RDRTIO.PovelyBlokovany"
node("RDRT", "central PLC (Tecomat TC700) and HMI", 1, 0, sources=[f"{SHARED}plc/rdrt_io.st"],
     allowed=False, groups=[
         {"name": "hmi", "clients": ["127.0.0.2"], "status_point": "COMM_HMI"},
         {"name": "ed", "clients": ["127.0.0.3"], "status_point": "COMM_ED",
          "refuse_commands_when": BLOCKED},
         {"name": "mrs", "clients": ["127.0.0.4"], "status_point": "COMM_MRS",
          "refuse_commands_when": BLOCKED},
         {"name": "service", "clients": ["127.0.0.5"], "status_point": "COMM_SERVIS",
          "refuse_commands_when": BLOCKED},
         {"name": "dispatch", "status_point": "COMM_DISPATCH", "refuse_commands_when": BLOCKED},
     ])
task("main", 100, ["RDRTIO"], 400)
for signal, variable in [
    ("RDRT_FV230", "DI0_FV230"), ("RDRT_FV110", "DI1_FV110"), ("RDRT_FV24", "DI2_FV24"),
    ("RDRT_G230_OK", "DI3_G230_OK"), ("RDRT_G110_OK", "DI4_G110_OK"), ("RDRT_G24_OK", "DI5_G24_OK"),
    ("RDRT_Rezerva_DI6", "DI6_Rezerva"), ("RDRT_Switch_ABB_OK", "DI7_ABB_OK"),
    ("RDRT_Switch_Korenix_Porucha", "DI8_Korenix_Porucha"),
    ("RDRT_Switch_Siemens_Porucha", "DI9_Siemens_Porucha"),
    ("RDRT_Dvere_NN", "P6_Dvere_NN"), ("RDRT_Dvere_VN", "P6_Dvere_VN"),
    ("RDRT_Dvere_T1", "P6_Dvere_T1"), ("RDRT_Dvere_T2", "P6_Dvere_T2"),
    ("module-fault:RDRT_P6", "PoruchaModul6"), ("module-fault:RDRT_P9", "PoruchaModul9"),
]:
    io(signal, f"RDRTIO.{variable}")
for ioa, variable, text in [
    (1, "SP1_FV230", "surge arrester FV230 tripped"),
    (2, "SP2_FV110", "surge arrester FV110 tripped"),
    (3, "SP3_FV24", "surge arrester FV24 tripped"),
    (4, "SP4_G230", "power supply G230 fault"),
    (5, "SP5_G110", "switch/supply G110 fault"),
    (6, "SP6_G24", "supply G24 fault"),
    (7, "SP7_Rezerva", "spare input DI6"),
    (8, "SP8_Korenix", "Korenix switch fault"),
    (9, "SP9_ABB", "ABB switch fault"),
    (10, "SP10_Siemens", "Siemens switch fault"),
]:
    # Spec 7.2: points 1..20 are sent invalid while module P9 is faulty or removed.
    point(f"RDRT_{variable}", "M_SP_TB_1", ioa, f"RDRTIO.{variable}", text,
          groups=[1], invalid_when="RDRTIO.PoruchaModul9")
point("RDRT_SP21_HMI_Mistne", "M_SP_TB_1", 21, "RDRTIO.HmiLokalne",
      "HMI local mode (set by command 2001)", groups=[1])
point("RDRT_SP24_PoruchaModul6", "M_SP_TB_1", 24, "RDRTIO.SP24_PoruchaModul6", "module P6 fault", groups=[1])
point("RDRT_SP25_PoruchaModul9", "M_SP_TB_1", 25, "RDRTIO.SP25_PoruchaModul9", "module P9 fault", groups=[1])
for ioa, variable, text in [
    (26, "SP26_Dvere_NN", "LV switchroom door open"),
    (27, "SP27_Dvere_VN", "HV switchroom door open"),
    (28, "SP28_Dvere_T1", "transformer chamber T1 door open"),
    (29, "SP29_Dvere_T2", "transformer chamber T2 door open"),
]:
    point(f"RDRT_{variable}", "M_SP_TB_1", ioa, f"RDRTIO.{variable}", text, groups=[1],
          invalid_when="RDRTIO.PoruchaModul6")
point("COMM_RH", "M_SP_TB_1", 32, None, "communication failure to the S7-1500 RH (TRUE = link down)", groups=[1])
point("COMM_RZS", "M_SP_TB_1", 33, None, "communication failure to the S7-1500 RZS (TRUE = link down)", groups=[1])
point("COMM_RH_DT", "M_SP_TB_1", 34, None, "communication failure to the S7-1500 RH in DT (TRUE = link down)", groups=[1])
point("COMM_RZS_DT", "M_SP_TB_1", 35, None, "communication failure to the S7-1500 RZS in DT (TRUE = link down)", groups=[1])
for ioa, name, text in [(38, "COMM_ED", "link to ED (electric dispatch) down"),
                        (39, "COMM_MRS", "link to MŘS down"),
                        (40, "COMM_HMI", "link to the local HMI down"),
                        (41, "COMM_SERVIS", "service link down"),
                        (42, "COMM_DISPATCH", "link to the dispatch systems DDTS/DŘT down")]:
    point(name, "M_SP_TB_1", ioa, None, text + " (no client connected)", groups=[1])
for k, board in enumerate(LIGHTING, start=1):
    point(f"COMM_{board}", "M_SP_TB_1", 49 + k, None,
          f"communication failure to lighting board {board} (TRUE = link down)", groups=[1])
command("RDRT_HMI_Mistne", "C_SC_NA_1", 2001, "RDRTIO.HmiLokalne", "HMI local mode on/off (spec 7.4)",
        from_groups=["hmi"])
link("RH", "RH1.1", "COMM_RH", republish=0)
link("RZS", "RZS1", "COMM_RZS", republish=0)
link("RH_DT", "RH-DT", "COMM_RH_DT", republish=0)
link("RZS_DT", "RZS-DT", "COMM_RZS_DT", republish=0)
for k, board in enumerate(LIGHTING, start=1):
    link(board, board, f"COMM_{board}", republish=10_000 + 100 * k)

# --------------------------------------------------------------------------------------
# RDA's LOGO!: its plant signals and the points it reports.
RDA_IO = [
    ("RDA_KHU1_Napeti_sit", "KHU1_NapetiSit"), ("RDA_KHU2_Napeti_DA", "KHU2_NapetiDA"),
    ("RDA_KHU3_Napeti_RZS", "KHU3_NapetiRZS"), ("RDA_KM1_Zapnut", "KM1_Zapnut"),
    ("RDA_KM2_Zapnut", "KM2_Zapnut"), ("RDA_SA1_Mistne", "SA1_Mistne"),
    ("RDA_SA1_Dalkove", "SA1_Dalkove"), ("RDA_KHVRDA_Havarijni_vypnuti", "HavarijniVyp"),
    ("RDA_DA_Bezi", "DA_Bezi"), ("RDA_DA_Pripraven", "DA_Pripraven"),
    ("RDA_DA_Porucha", "DA_Porucha"), ("RDA_FV1_Prepetova_ochrana", "FV1_PrepetovaOchrana"),
    ("RDA_FU1_Pretavena_pojistka", "FU1_PretavenaPojistka"),
    ("RDA_KM1_Zap", "KM1_Zap"), ("RDA_KM2_Zap", "KM2_Zap"), ("RDA_DA_Start", "DA_Start"),
]
RDA_POINTS = [
    (401, "KM1_Zapnut", "contactor KM1 (supply from RH1.1, mains) closed"),
    (402, "KM2_Zapnut", "contactor KM2 (supply from the diesel generator) closed"),
    (403, "KHU1_NapetiSit", "mains voltage present"),
    (404, "KHU2_NapetiDA", "generator voltage present"),
    (405, "KHU3_NapetiRZS", "RZS busbar voltage present"),
    (406, "SA1_Mistne", "selector SA1 in local"),
    (407, "SA1_Dalkove", "selector SA1 in remote"),
    (408, "HavarijniVyp", "emergency off of RDA"),
    (409, "DA_Bezi", "generator running"),
    (410, "DA_Pripraven", "generator ready (voltage settled)"),
    (411, "DA_Porucha", "generator failed to start"),
    (412, "FV1_PrepetovaOchrana", "surge protection FV1 tripped"),
    (413, "FU1_PretavenaPojistka", "fuse FU1 blown"),
    (414, "NaSiti", "RZS fed from the mains"),
    (415, "NaDA", "RZS fed from the diesel generator"),
    (416, "BezNapeti", "RZS without supply"),
    (417, "Porucha", "transfer fault (summary)"),
    (418, "Porucha_DA", "generator fault"),
    (419, "Porucha_KM1", "contactor KM1 does not follow its coil"),
    (420, "Porucha_KM2", "contactor KM2 does not follow its coil"),
]
RDA_STAV_TEXT = ("transfer state: 0 start, 1 mains, 2 generator starting, 3 settling, "
                 "4 on generator, 5 returning, 9 emergency off")


def rda_board(port_offset):
    node("RDA", "transfer board mains / diesel generator (LOGO!)", 23, port_offset,
         sources=[f"{SHARED}plc/rda_transfer.st"])
    task("main", 10, ["RDATransfer"], 100)
    for signal, variable in RDA_IO:
        io(signal, f"RDATransfer.{variable}")


if not S7:
    # ----------------------------------------------------------------------------------
    concentrator_node("RH1.1", "main board concentrator (S7-1500)", 11, 1)
    point("COMM_RH2", "M_SP_TB_1", 280, None, "communication failure to the LOGO! of RH2")
    point("COMM_RH12", "M_SP_TB_1", 320, None, "communication failure to the LOGO! of RH1.2")
    link("RH2", "RH2", "COMM_RH2", republish=0)
    link("RH1.2", "RH1.2", "COMM_RH12", republish=40)

    power_board("RH2", "RH2", 21, 2, "board RH2 (LOGO!), fed from T2")
    power_board("RH1.2", "RH12", 24, 6, "board RH1.2 (LOGO!), fed from RH1.1")

    concentrator_node("RZS1", "standby-supply board concentrator (S7-1500)", 12, 3)
    point("COMM_RZZ", "M_SP_TB_1", 380, None, "communication failure to the LOGO! of RZZ")
    point("COMM_RDA", "M_SP_TB_1", 400, None, "communication failure to the LOGO! of RDA")
    point("COMM_RZS2", "M_SP_TB_1", 440, None, "communication failure to the LOGO! of RZS2")
    link("RZZ", "RZZ", "COMM_RZZ", republish=100)
    link("RDA", "RDA", "COMM_RDA", republish=0)
    link("RZS2", "RZS2", "COMM_RZS2", republish=160)

    power_board("RZZ", "RZZ", 22, 4, "board RZZ (LOGO!), fed from T1 (TZ1)")
    power_board("RZS2", "RZS2", 25, 7, "board RZS2 (LOGO!), fed from RZS")

    # ----------------------------------------------------------------------------------
    rda_board(5)
    for ioa, variable, text in RDA_POINTS:
        point(f"RDA_{variable}", "M_SP_TB_1", ioa, f"RDATransfer.{variable}", text)
    point("RDA_Stav", "M_ME_TE_1", 421, "RDATransfer.Stav", RDA_STAV_TEXT)
    command("RDA_ProvozDA", "C_SC_NA_1", 2201, "RDATransfer.Cmd_ProvozDA",
            "run RZS from the diesel generator (test run; level, held until switched off)",
            remote_enable="RDATransfer.SA1_Dalkove")
else:
    # ----------------------------------------------------------------------------------
    # The S7 variant: each concentrator serves its PLC memory over S7 ([node.s7_server],
    # port_base + 50 and + 51 here, 102 on the S7-1500s); its LOGO! boards connect to it
    # as S7 clients with the TSAPs of the thesis's connection table (3.3: local IDs
    # 100-102, here the called TSAPs 0100-0102) and write their inputs into its markers
    # (tag list 6.1: RH2 at M20.0-M22.1, commands M24.0/M24.1), where the concentrator's
    # tag table declares them. The other boards (not in the thesis's lists, ours): RH1.2
    # at RH1.1 as RH2 ten bytes up (M30.0-M32.1, commands M34.0/M34.1); RZZ at RZS1 as RH2
    # at RH1.1 (5.2: "the RH2 pattern"), RZS2 ten bytes up from RDA (M50.0-M52.1, M54.0/
    # M54.1), RDA at M40.0-M42.3, its state at MW44, its command at M46.0. The boards'
    # meters (IOA 271-274, ours) are not in the transfer areas. Against real LOGO!s the
    # board nodes go and the concentrators listen on 102.
    def tag(name):
        """A tag's name as an ST identifier (FA1.1 -> FA1_1)."""
        return name.replace(".", "_")

    def marker(index, first_byte):
        return f"{first_byte + index // 8}.{index % 8}"

    def board_tags(board, first_byte):
        """(tag, marker bit, text, board program variable) of a power board's inputs."""
        shown = "RH1.2" if board == "RH12" else board  # the plant's prefix, the thesis's name
        return [(f"{board}_{tag(suffix.replace('{B}', board))}", marker(i, first_byte),
                 text.replace("{B}", shown), variable)
                for i, (suffix, variable, text) in enumerate(BOARD_INPUTS)]

    def concentrator(name, description, ca, port_offset, s7_offset, connections):
        """connections: (thesis connection name, board prefix, called TSAP, status IOA)."""
        program = concentrator_node(name, description, ca, port_offset)
        table("node.s7_server", port_offset=s7_offset, markers=64)
        for connection, board, tsap, ioa in connections:
            table("[[node.s7_server.connection]]", name=connection, tsap=tsap,
                  status=f"{program}.Comm_{board}")
            PROGRAMS[program].append((f"Comm_{board}", None, "BOOL := TRUE",
                                      f"LOGO!8_{connection} not connected (S7_Connection_{connection})"))
            point(f"COMM_{board}", "M_SP_TB_1", ioa, f"{program}.Comm_{board}",
                  f"communication failure to the LOGO! of {connection} (S7 connection)")
        return program

    def concentrated_board(program, board, ioa_base, first_byte, commands):
        tags = board_tags(board, first_byte)
        for i, ((name, bit, text, _), (suffix, _, _)) in enumerate(zip(tags, BOARD_INPUTS)):
            PROGRAMS[program].append((name, f"%MX{bit}", "BOOL", text))
            # the points keep the plain project's names (RH2_V1_FA1.1), the tags are ST names
            point(f"{board}_{suffix.replace('{B}', board)}", "M_SP_TB_1", ioa_base + i,
                  f"{program}.{name}", text, invalid_when=f"{program}.Comm_{board}")
        remote = f"{program}.{board}_P1_SA1_Dalkove"
        for bit, (ioa, suffix, text) in enumerate(commands):
            address = f"%MX{first_byte + 4}.{bit}"
            PROGRAMS[program].append((f"{board}_{suffix}", address, "BOOL", text))
            command(f"{board}_{suffix}", "C_SC_NA_1", ioa, address, text,
                    remote_enable=remote, pulse_ms=500)

    def qf1_commands(ioa):
        return [(ioa, "VypnoutQF1", "open QF1"), (ioa + 1, "ZapnoutQF1", "close QF1")]

    def device_io(device, item, direction, variable):
        table("[[node.io]]", device=device, item=item, direction=direction, variable=variable)

    def s7_device(concentrator_node, tsap):
        name = f"S7_{tag(concentrator_node)}"
        table("[[node.device]]", name=name, kind="s7",
              description=f"S7 connection to the S7-1500 of {concentrator_node}", ioa_base=900,
              settings={"connect": f"node:{concentrator_node}", "tsap": f"0200:{tsap}",
                        "cycle_ms": 50})
        return name

    def logo_board(name, board, ca, description, concentrator_node, tsap, first_byte):
        program = LOGO
        node(name, description, ca, None, sources=[f"{SHARED}{LOGO_SOURCE}"])
        task("main", 10, [program], 100)
        for suffix, variable, _ in BOARD_INPUTS:
            io(f"{board}_{suffix.replace('{B}', board)}", f"{program}.{variable}")
        io(f"{board}_QF1_Zapnut", f"{program}.QF1_Zapnut")
        io(f"{board}_QF1_Vyp", f"{program}.QF1_OFF")
        io(f"{board}_QF1_Zap", f"{program}.QF1_ON")
        device = s7_device(concentrator_node, tsap)
        for _, bit, _, variable in board_tags(board, first_byte):
            device_io(device, f"M{bit}", "output", f"{program}.{variable}")
        device_io(device, f"M{first_byte + 4}.0", "input", f"{program}.Cmd_VypnoutQF1")
        device_io(device, f"M{first_byte + 4}.1", "input", f"{program}.Cmd_ZapnoutQF1")

    concentrator("RH1.1", "main board concentrator (S7-1500): S7 server of LOGO! RH2 and RH1.2",
                 11, 1, 50, [("RH2", "RH2", "0101", 280), ("RH1.2", "RH12", "0100", 320)])
    concentrated_board("RH11Concentrator", "RH2", 281, 20, qf1_commands(2021))
    concentrated_board("RH11Concentrator", "RH12", 321, 30, qf1_commands(2061))
    logo_board("RH2", "RH2", 21, "board RH2 (LOGO!), fed from T2", "RH1.1", "0101", 20)
    logo_board("RH1.2", "RH12", 24, "board RH1.2 (LOGO!), fed from RH1.1", "RH1.1", "0100", 30)

    concentrator("RZS1", "standby-supply board concentrator (S7-1500): S7 server of LOGO! RZZ, "
                 "RDA and RZS2", 12, 3, 51,
                 [("RZZ", "RZZ", "0101", 380), ("RDA", "RDA", "0102", 400),
                  ("RZS2", "RZS2", "0100", 440)])
    concentrated_board("RZS1Concentrator", "RZZ", 381, 20, qf1_commands(2121))
    for i, (ioa, variable, text) in enumerate(RDA_POINTS):
        name = f"RDA_{variable}"
        PROGRAMS["RZS1Concentrator"].append((name, f"%MX{marker(i, 40)}", "BOOL", text))
        point(name, "M_SP_TB_1", ioa, f"RZS1Concentrator.{name}", text,
              invalid_when="RZS1Concentrator.Comm_RDA")
    PROGRAMS["RZS1Concentrator"].append(("RDA_Stav", "%MW44", "INT", "transfer state"))
    point("RDA_Stav", "M_ME_TE_1", 421, "RZS1Concentrator.RDA_Stav", RDA_STAV_TEXT,
          invalid_when="RZS1Concentrator.Comm_RDA")
    PROGRAMS["RZS1Concentrator"].append(("RDA_ProvozDA", "%MX46.0", "BOOL",
                                         "command: run RZS from the diesel generator"))
    command("RDA_ProvozDA", "C_SC_NA_1", 2201, "%MX46.0",
            "run RZS from the diesel generator (test run; level, held until switched off)",
            remote_enable="RZS1Concentrator.RDA_SA1_Dalkove")
    concentrated_board("RZS1Concentrator", "RZS2", 441, 50, qf1_commands(2181))

    logo_board("RZZ", "RZZ", 22, "board RZZ (LOGO!), fed from T1 (TZ1)", "RZS1", "0101", 20)
    logo_board("RZS2", "RZS2", 25, "board RZS2 (LOGO!), fed from RZS", "RZS1", "0100", 50)
    rda_board(None)
    device = s7_device("RZS1", "0102")
    for i, (_, variable, _) in enumerate(RDA_POINTS):
        device_io(device, f"M{marker(i, 40)}", "output", f"RDATransfer.{variable}")
    device_io(device, "MW44:INT", "output", "RDATransfer.Stav")
    device_io(device, "M46.0", "input", "RDATransfer.Cmd_ProvozDA")

# --------------------------------------------------------------------------------------
# The S7-1500s in DT: RH and RZS of the transport terminal (spec 2.1, 3.1), reporting
# their own I/O to the TC700 over IEC 104 (7.5: its master links to RH and RZS, TO and
# DT). The third S7-1500 there, the OŘ-area lighting, is the lighting board OR below.
concentrator_node("RH-DT", "RH board concentrator in DT (S7-1500), fed from RH1.1", 13, 8,
                  shared=True)
concentrator_node("RZS-DT", "RZS board concentrator in DT (S7-1500), fed from RZS", 14, 9,
                  shared=True)

# --------------------------------------------------------------------------------------
LIGHTING_INPUTS = [
    ("Dalkove", "Dalkove"), ("Cidlo", "Cidlo"), ("PrRele", "PrRele"),
    ("KM1_Zapnut", "KM1_Zapnut"), ("Rucne_Zap", "Rucne_Zap"), ("Dvere", "Dvere"),
    ("Termostat_Min", "Termostat_Min"), ("Termostat_Max", "Termostat_Max"),
    ("FV1_Prepetova_ochrana", "FV1_PrepetovaOchrana"),
    ("FU1_Pretavena_pojistka", "FU1_PretavenaPojistka"), ("Napeti", "Napeti"),
    ("P_kW", "P_kW"), ("Energie_kWh", "Energie_kWh"),
]
LIGHTING_POINTS = [
    (1, "Dalkove", "LightingBoard.Dalkove", "remote control enabled"),
    (2, "Zap_Z_Rozvadece", "LightingBoard.Vystupy.Zap_Z_Rozvadece", "lighting under local (cabinet) control"),
    (3, "Osv_Rucne", "LightingBoard.Vystupy.Osv_Rucne", "manual mode in force"),
    (4, "Set_Astral", "LightingBoard.Vystupy.Set_Astral", "astronomical mode in force"),
    (5, "Set_Cidlo", "LightingBoard.Vystupy.Set_Cidlo", "dusk-sensor mode in force"),
    (6, "Set_Cas", "LightingBoard.Vystupy.Set_Cas", "time-window mode in force"),
    (7, "Zap_Rucne", "LightingBoard.Vystupy.Zap_Rucne", "lit by manual command"),
    (8, "Zap_Astral", "LightingBoard.Vystupy.Zap_Astral", "astronomical criterion: dark"),
    (9, "Zap_Cidlo", "LightingBoard.Vystupy.Zap_Cidlo", "dusk-sensor criterion: dark"),
    (10, "Zap_Cas", "LightingBoard.Vystupy.Zap_Cas", "inside a time window"),
    (11, "Osv_Zap", "LightingBoard.Vystupy.Osv_Zap", "lighting ON command"),
    (12, "PrRele", "LightingBoard.PrRele", "lamp-circuit feedback relay"),
    (13, "Osv_Por", "LightingBoard.Vystupy.Osv_Por", "lighting-circuit fault"),
    (14, "KM1_Zapnut", "LightingBoard.KM1_Zapnut", "lighting contactor KM1 closed"),
    (15, "Porucha_KM1", "LightingBoard.Porucha_KM1", "contactor KM1 does not follow its coil"),
    (16, "Dvere", "LightingBoard.Dvere", "cabinet door open"),
    (17, "Termostat_Min", "LightingBoard.Termostat_Min", "cabinet thermostat min"),
    (18, "Termostat_Max", "LightingBoard.Termostat_Max", "cabinet thermostat max"),
    (19, "FV1_Prepetova_ochrana", "LightingBoard.FV1_PrepetovaOchrana", "surge arrester tripped"),
    (20, "FU1_Pretavena_pojistka", "LightingBoard.FU1_PretavenaPojistka", "lamp-circuit fuse blown"),
    (21, "Napeti", "LightingBoard.Napeti", "board supply present"),
    (22, "Cidlo", "LightingBoard.Cidlo", "dusk sensor: dark"),
]
LIGHTING_COMMANDS = [
    (51, "W_Rucne", "C_SC_NA_1", "LightingBoard.Vstupy.W_Rucne", "request manual mode", {}),
    (52, "W_ZapRucne", "C_SC_NA_1", "LightingBoard.Vstupy.W_ZapRucne", "manual on/off", {}),
    (53, "W_Astral", "C_SC_NA_1", "LightingBoard.Vstupy.W_Astral", "enable astronomical mode", {}),
    (54, "W_Cidlo", "C_SC_NA_1", "LightingBoard.Vstupy.W_Cidlo", "enable dusk-sensor mode", {}),
    (55, "W_Cas", "C_SC_NA_1", "LightingBoard.Vstupy.W_Cas", "enable time-window mode", {}),
    (56, "W_SetTime", "C_SC_NA_1", "LightingBoard.Vstupy.W_SetTime",
     "take over the four window times (strobe)", {"pulse_ms": 1000}),
    (61, "W_Cas1Zap", "C_SE_NB_1", "LightingBoard.Cas1Zap_min", "window 1 on, minutes after midnight", {"range": [0, 1439]}),
    (62, "W_Cas1Vyp", "C_SE_NB_1", "LightingBoard.Cas1Vyp_min", "window 1 off, minutes after midnight", {"range": [0, 1439]}),
    (63, "W_Cas2Zap", "C_SE_NB_1", "LightingBoard.Cas2Zap_min", "window 2 on, minutes after midnight", {"range": [0, 1439]}),
    (64, "W_Cas2Vyp", "C_SE_NB_1", "LightingBoard.Cas2Vyp_min", "window 2 off, minutes after midnight", {"range": [0, 1439]}),
]

for k, board in enumerate(LIGHTING, start=1):
    what = "OŘ-area lighting (S7-1500 in DT)" if board == "OR" else f"lighting tower board {board} (S7-1200)"
    node(board, what, 100 + k, 9 + k, sources=[f"{SHARED}plc/osvetleni.st", f"{SHARED}plc/lighting_board.st"])
    task("main", 100, ["LightingBoard"], 400)
    # Staggered switch-on (spec 4.9, RS-A8: index x 2 s); astronomical mode until the
    # dispatch sets another.
    table("node.set", **{'"LightingBoard.Zpozdeni"': f"T#{2 * k}s",
                         '"LightingBoard.Vstupy.W_Astral"': "TRUE"})
    # The weekly calendar is data (spec 4.4): generated for Vsetín by
    # `cargo run -p plant --example lighting_calendar`, replaceable by the official E 11 file.
    table("[[node.table]]", file=f"{SHARED}calendar/vsetin-weekly.csv", index="week",
          columns={"off_utc": "LightingBoard.Osvetleni.sunrise_data",
                   "on_utc": "LightingBoard.Osvetleni.sunset_data"})
    for suffix, variable in LIGHTING_INPUTS:
        io(f"{board}_{suffix}", f"LightingBoard.{variable}")
    io(f"{board}_OvladanyQ", "LightingBoard.OvladanyQ")
    for n, name, source, text in LIGHTING_POINTS:
        point(f"{board}_{name}", "M_SP_TB_1", n, source, text)
    point(f"{board}_P_kW", "M_ME_TF_1", 31, "LightingBoard.P_kW", "lamp power, kW", deadband=0.1)
    point(f"{board}_Energie_kWh", "M_ME_TF_1", 32, "LightingBoard.Energie_kWh", "lamp energy, kWh", deadband=0.5)
    for n, name, type_id, target, text, extra in LIGHTING_COMMANDS:
        command(f"{board}_{name}", type_id, n, target, text,
                remote_enable="LightingBoard.Dalkove", **extra)

OUT.parent.mkdir(parents=True, exist_ok=True)
OUT.write_text("\n".join(out).rstrip() + "\n", encoding="utf-8")
print(f"wrote {OUT}")
for program, tags in PROGRAMS.items():
    if S7 and program in SHARED_PROGRAMS:
        continue
    lines = [f"(* The tag table of the S7-1500 concentrator {program} (the railway-station thesis,",
             "   sections 5.4, 5.5 and 6.1): its own inputs, which the station binds to the plant",
             "   ([[node.io]]), and in examples/vsetin-s7 the markers its LOGO! boards write over",
             "   their S7 connections, the commands they read and each connection's status (set",
             "   by the station's S7 server). Written by",
             "   examples/vsetin/tools/generate_station_toml.py. *)",
             "", f"PROGRAM {program}", "VAR"]
    for name, address, type_, comment in tags:
        at = f" AT {address}" if address else ""
        lines.append(f"    {name}{at} : {type_};  (* {comment} *)")
    lines += ["END_VAR", "END_PROGRAM", ""]
    path = OUT.parent / "plc" / f"{program.lower()}.st"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines), encoding="utf-8")
    print(f"wrote {path}")
