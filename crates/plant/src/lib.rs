//! Plant simulations: the physical equipment and field devices a PLC is wired to, without
//! any control logic.
//!
//! Every plant implements [`Plant`]: its named I/O, its I/O modules and their faults, and
//! its own console language for fault injection and hand operations, described by the
//! plant ([`Plant::console_operations`], [`Plant::status`]). The runtime finds a plant by
//! the project's `plant = "..."` key in [`registry`] and knows no plant by name; adding
//! one (the ball sorter, a lift) is a module here and a registry entry.
//!
//! The four EDU-mod models of the PLC teaching lab (the teaching-lab thesis,
//! docs/THESES.md: slide unit, crossroad, mixing unit, washing machine) are in [`lab`],
//! with their ERR/RESET behaviour, error record and the address tables of the lab; the
//! registry opens them as `slide`, `crossroad`, `mixing` and `washing`.
//!
//! The sorting lab's ball sorter (the sorting-lab thesis) is [`sorter`]: the mechanism
//! behind its supervisor, with the balance simulator on its pan; the registry opens it as
//! `sorter`.
//!
//! The first plant, [`vsetin`], is the Vsetín railway station (the railway-station thesis,
//! docs/THESES.md: the station's supply, lighting, boards and dispatch): its 6 kV feeds, transformers, distribution boards, diesel generator set,
//! lighting towers and their contacts, relays and meters. The transfer logic (RDA), the
//! breaker command logic (RH2/RZZ) and the lighting function block are *not* here: they
//! run as Structured Text in the soft PLC, read this plant's inputs and drive its outputs
//! through an I/O image.
//!
//! # Design
//!
//! - **Sans-IO and clock-free.** A plant never reads a clock. Simulated time ([`SimTime`],
//!   a `Duration` since the start) moves only through [`Plant::advance_to`] /
//!   [`Plant::advance`], so a year runs in a fraction of a second and tests are exact.
//! - **Event-exact.** Every device keeps absolute deadlines (breaker operate time,
//!   contactor pick-up, relay delay, generator start and voltage breakpoints, lamp
//!   warm-up, dusk-sensor crossings). `advance_to(t)` walks from deadline to deadline and
//!   never overshoots one, so the result does not depend on the step size (tested: 1 ms,
//!   7 ms, 3 s and event-to-event stepping give identical inputs). [`Plant::next_event`]
//!   lets a scheduler jump straight to the next change. Analog values that move between
//!   events (generator voltage, light output, illuminance) are exact functions of time;
//!   energy meters count on-time in whole nanoseconds.
//! - **One settle order per instant.** At each instant the plant (1) fires due deadlines,
//!   (2) applies coils, commands and hard-wired interlocks to breakers, contactors and the
//!   generator, (3) recomputes energisation, (4) drives the relays and lamp circuits that
//!   sense it. Dependencies only go forward, so one pass is consistent.
//! - **A named I/O surface.** Every physical signal has a stable name ([`SignalInfo`]),
//!   a direction seen from the PLC ([`Direction::Input`]: contacts, relays, measurements;
//!   [`Direction::Output`]: coils and commands), a type ([`Value`]) and the I/O module it
//!   is wired to. [`Plant::read`] returns a [`Reading`] whose `valid` flag is false while
//!   that module is pulled or unreachable: the runtime turns it into IV quality.
//! - **Energisation through a topology.** Buses, links (breakers, contactors,
//!   transformers, cables) and sources form an undirected graph; a bus is live if and only
//!   if closed links join it to a live source ([`VsetinPlant::topology`]). A wrong closure
//!   back-feeds as it would in the field.
//! - **A safety monitor that records, never prevents.** When sources of different groups
//!   (grid: `TNS_USTI`, `TNS_VALMEZ`, `UTILITY`; diesel: `DA`) are joined by closed links,
//!   or a breaker gets both coils at once, a [`SafetyEvent`] is logged
//!   ([`VsetinPlant::safety_log`]), so scenario tests can assert "never both sources
//!   closed" against whatever the PLC program did.
//! - **Faults and hand operations** are values ([`Fault`], [`Action`]) with a text form
//!   (`supply-loss T1`, `stuck-open RDA_KM2`), for tests, the CLI and the HMI. A device
//!   may be named by a unique short form of its name (`module-pulled p9` for `RDRT_P9`,
//!   [`VsetinPlant::resolve_device`]); [`operation_syntax`] and
//!   [`VsetinPlant::device_names`] tell which names each fault and operation takes.
//! - **Deterministic**: no wall clock, no randomness. The sun is a closed-form model.
//! - **No panics** on any input: unknown names, wrong types and time going backwards are
//!   [`PlantError`]s.
//!
//! The [`Plant`] trait is the shape other plants will share (the lab models and the ball
//! sorter): named BOOL/REAL signals with modules, `advance_to`/`next_event`, `read`/
//! `set_output`. Faults and hand operations are plant-specific types.
//!
//! # The station model
//!
//! ```text
//!  TNS_USTI ─LINE─ R6_USTI ─R6_Q1─┐            ┌─T1 (TZ1)─ T1_LV ─QF1─ RZZ ─FA1─ RZZ_V1 ─FA1.1..5─ RZZ_F1..5
//!                     └──RS602──┐  ├─ R6 ─R6_Q3─ R6_T ┤                  │  └─TI_RZZA─ RZZ_A (autoblock)
//!  TNS_VALMEZ ─LINE─ R6_VALMEZ ─R6_Q2┘  └──────────┘ │                  └─UZ_K1─┐
//!                                    (RS602 by-passes R6)                        ├─ SZZ (signalling equipment)
//!                                                  └─T2─ T2_LV ─QF1─ RH2 ─FA1─ RH2_V1 ─FA1.1─ RH2_F1 ─ ROV01..03
//!                                                                      │       ├FA1.2─ RH2_F2 ─ ROV04..06
//!                                                                      │       ├FA1.3─ RH2_F3 ─ ROV07..09
//!                                                                      │       ├FA1.4─ RH2_F4 ─ ROV10..12
//!                                                                      │       └FA1.5─ RH2_F5 ─ OR
//!  UTILITY ─RH11_QF1─ RH11 ─RDA_KM1─┐                                    │
//!             ├─TI_RH11─ RH11_AB     ├─ RZS (board RZS1) ─UZ_K2──────────┘ (backup of SZZ)
//!             ├─QF1─ RH12 (RH1.2)    │    ├─QF1─ RZS2
//!             └─QF1─ RHDT (RH in DT) │    └─QF1─ RZSDT (RZS in DT)
//!  DA (diesel set) ───────RDA_KM2───┘
//! ```
//!
//! Where the spec is silent the model makes a documented choice: which RH2 branch feeds
//! which tower (above); what RS602 bridges (the line from TNS Ústí to the transformers'
//! 6 kV side, so that R6 can be taken out: it closes by hand only while R6_Q3 is open, and
//! R6_Q3 only while RS602 is open); that the thesis's TZ1 (the 6/0.4 kV transformer of the
//! signalling supply, feeding RZZ) is the transformer of chamber T1; the universal
//! source's changeover (RZZ preferred, RZS1 as backup, break before make); where RH1.2,
//! RZS2 and the DT boards are fed from (above) and which DI module reports what; QF1
//! auxiliary contacts `RH2_QF1_Zapnut`/`RZZ_QF1_Zapnut` (not in
//! the thesis tag list), the RDA contactors KM1/KM2 and their relays, the completion of the
//! truncated tag names (`…_Napeti_na_privodu`, `…_Napeti_na_pripojeni`,
//! `…_Havarijni_vypnuti`, `…_Prepetova_ochrana`, `…_Napeti_zdroje`), the loads and all
//! times.
//!
//! ## Devices and default times ([`StationConfig`])
//!
//! | Device | Behaviour | Default |
//! |---|---|---|
//! | Motorised breaker QF1 (RH2, RZZ) | closes on the *rising edge* of the close coil (anti-pumping), opens on the trip coil; trip-free (trip wins, aborts a closing); emergency-off trips it through a hard-wired release and blocks closing; door pushbuttons work only with SA1 in local | close 60 ms, open 40 ms |
//! | Motorised breaker QF1 of RH1.2 and RZS2 | as RH2's (the same LOGO! board) | close 60 ms, open 40 ms |
//! | Manual breakers FA, `RH11_QF1`, `RHDT_QF1`, `RZSDT_QF1`, the R6 cubicles `R6_Q1..3` and the by-pass disconnector box `RS602` | closed at start (RS602 open); open on a trip fault (after the open time) or by hand; reclosed by hand or by clearing the trip; RS602 and R6_Q3 lock each other out (a hand close is refused while the other is closed) | open 40 ms |
//! | Universal source of the signalling equipment (`UZ_K1` from RZZ, `UZ_K2` from RZS1) | K1 follows RZZ's voltage; K2 closes only while RZZ is dead and K1 open, and opens when RZZ returns (then K1 closes): never both | relays 20 ms, contactors as below |
//! | Contactors (`RDA_KM1`, `RDA_KM2`, `{L}_KM1`, manual `{L}_KM2`) | follow the coil; a pulse shorter than the pick-up does nothing; RDA's emergency-off cuts both coils | pick-up 30 ms, drop-out 20 ms |
//! | Voltage relays KHU | follow their bus (or the generator's ≥ 90 % voltage) | 20 ms both ways |
//! | Lamp feedback relay `PrRele` | picks up when the lamp circuit is energised and healthy, drops at once | pick-up 50 ms |
//! | Lamps | light output ramps 0 → 100 % over the warm-up; constant electrical power while energised | 3 s; tower 2.4 kW, OŘ 6 kW |
//! | Diesel set | start request (level) → cranking → running at start delay; voltage linear to 90 % at +`voltage_build`, overshoot 106 % mid-way, settled (`RDA_DA_Pripraven`) at +`settle`; start removed → runs unloaded for the cool-down, then stops; fail-to-start fault → `RDA_DA_Porucha` at the start delay, retried when the fault clears | 5 s, 1 s, 6 s, cool-down 60 s, 400 V |
//! | Dusk sensors | "dark" below 20 lx; the sky is a NOAA sunrise/sunset for Vsetín with linear twilight ramps (0 lx at sunrise − 30 min, 1,000 lx at + 30 min), so switching instants are exact; [`Action::SetIlluminance`] forces a value | 20 lx |
//! | Meters | board meters count their own base load while the bus is live; tower meters the lamps | RH1.1 15 kW, RZZ 8, RZS 10, RH2 5, RH1.2 6, RZS2 4, RH in DT 20, RZS in DT 6, signalling equipment 4 |
//!
//! The initial state is steady: grid live, QF1 and FA closed, relays picked up, RDA
//! contactors open (the PLC closes one), generator stopped, all selectors in remote, time
//! zero = 2024-01-01T00:00Z (for the sun only).
//!
//! # Signal table
//!
//! `{B}` stands for the LOGO! boards `RH2`, `RZZ`, `RH12` (RH1.2) and `RZS2`; `{D}` for
//! the boards in DT, `RHDT` and `RZSDT`; `{L}` for the lighting boards `ROV01`…`ROV12` and
//! `OR`; `{a..b}` for each integer of the range. [`signal_table_markdown`] renders the
//! full expanded list. Inputs are what the PLC reads, outputs what it drives.
//!
//! | Signal | Dir | Type | Module | Meaning |
//! |---|---|---|---|---|
//! | `{B}_QF1_Vyp` | out | BOOL | `{B}_LOGO` | trip coil of feeder breaker QF1 (DO "QF1 off") |
//! | `{B}_QF1_Zap` | out | BOOL | `{B}_LOGO` | close coil of QF1 (DO "QF1 on"; the rising edge closes) |
//! | `{B}_QF1_Zapnut` | in | BOOL | `{B}_LOGO` | QF1 closed (auxiliary contact) |
//! | `{B}_V1_FA1_Zapnut` | in | BOOL | `{B}_LOGO` | branch breaker FA1 closed (IOA 281 for RH2) |
//! | `{B}_V1_FA1.{1..5}` | in | BOOL | `{B}_LOGO` | branch breakers FA1.1–FA1.5 closed (IOA 282–286) |
//! | `{B}_P1_FA110.{0..2}` | in | BOOL | `{B}_LOGO` | 110 V DC breakers closed (IOA 287–289) |
//! | `{B}_P1_KHU1_Napeti_na_privodu` | in | BOOL | `{B}_LOGO` | voltage on the incoming feeder, upstream of QF1 (IOA 290) |
//! | `{B}_P1_KHU3_Napeti_na_pripojeni` | in | BOOL | `{B}_LOGO` | voltage on the busbar, downstream of QF1 (IOA 291) |
//! | `{B}_P1_SA1_Mistne` | in | BOOL | `{B}_LOGO` | selector SA1 in local (IOA 292) |
//! | `{B}_P1_SA1_Dalkove` | in | BOOL | `{B}_LOGO` | selector SA1 in remote (IOA 293) |
//! | `{B}_P1_FU1_Pretavena_pojistka` | in | BOOL | `{B}_LOGO` | fuse FU1 blown (IOA 294) |
//! | `{B}_P1_FV1_Prepetova_ochrana` | in | BOOL | `{B}_LOGO` | surge arrester FV1 tripped (IOA 295) |
//! | `RH2_P1_KHVRH2_Havarijni_vypnuti`, `RZZ_P1_KHVRZZ_Havarijni_vypnuti`, `RH12_P1_KHVRH12_Havarijni_vypnuti`, `RZS2_P1_KHVRZS2_Havarijni_vypnuti` | in | BOOL | `{B}_LOGO` | emergency off pressed (IOA 296) |
//! | `{B}_P1_FV110_Prepetova_ochrana` | in | BOOL | `{B}_LOGO` | surge arrester FV110 tripped (IOA 297) |
//! | `{B}_P1_G110.2_Napeti_zdroje` | in | BOOL | `{B}_LOGO` | 110 V source G110.2 healthy (IOA 298) |
//! | `{B}_RezervaVstup{1..14}` | in | BOOL | `{B}_LOGO` | spare inputs, always FALSE |
//! | `{B}_U` | in | REAL V | `{B}_LOGO` | busbar voltage |
//! | `{B}_P_kW`, `{B}_I_A`, `{B}_Energie_kWh` | in | REAL | `{B}_LOGO` | own load power, phase current and energy meter |
//! | `RH11_QF1_Zapnut` | in | BOOL | `RH11_DI` | main breaker on the utility feed closed |
//! | `RH11_KHU1_Napeti_sit` | in | BOOL | `RH11_DI` | utility voltage present |
//! | `RH11_FV1_Prepetova_ochrana`, `RH11_FU1_Pretavena_pojistka` | in | BOOL | `RH11_DI` | surge arrester tripped, fuse blown |
//! | `RH11_U`, `RH11_P_kW`, `RH11_I_A`, `RH11_Energie_kWh`, `R6_U` | in | REAL | `RH11_DI` | busbar voltage, power, current, energy; 6 kV switchroom voltage |
//! | `R6_T_U` | in | REAL V | `RH11_DI` | 6 kV voltage at the transformers (through R6 or RS602) |
//! | `R6_Q1_Zapnut`, `R6_Q2_Zapnut`, `R6_Q3_Zapnut` | in | BOOL | `RH11_DI` | R6 cubicles closed: incomers from TNS Ústí and TNS Valašské Meziříčí, transformer feeder |
//! | `RS602_Zapnut` | in | BOOL | `RH11_DI` | by-pass disconnector box RS602 closed |
//! | `RDA_KM1_Zap` | out | BOOL | `RDA_LOGO` | coil of KM1, supply of RZS from RH1.1 (mains) |
//! | `RDA_KM2_Zap` | out | BOOL | `RDA_LOGO` | coil of KM2, supply of RZS from the diesel set |
//! | `RDA_DA_Start` | out | BOOL | `RDA_LOGO` | generator start/run request (level) |
//! | `RDA_KM1_Zapnut`, `RDA_KM2_Zapnut` | in | BOOL | `RDA_LOGO` | contactors closed (auxiliary contacts) |
//! | `RDA_KHU1_Napeti_sit` | in | BOOL | `RDA_LOGO` | mains voltage present on the RH1.1 side |
//! | `RDA_KHU2_Napeti_DA` | in | BOOL | `RDA_LOGO` | generator voltage ≥ 90 % |
//! | `RDA_KHU3_Napeti_RZS` | in | BOOL | `RDA_LOGO` | RZS busbar voltage present |
//! | `RDA_SA1_Mistne`, `RDA_SA1_Dalkove` | in | BOOL | `RDA_LOGO` | selector SA1 local / remote |
//! | `RDA_KHVRDA_Havarijni_vypnuti` | in | BOOL | `RDA_LOGO` | emergency off (cuts both contactor coils) |
//! | `RDA_DA_Bezi` | in | BOOL | `RDA_LOGO` | generator engine running |
//! | `RDA_DA_Pripraven` | in | BOOL | `RDA_LOGO` | generator voltage settled, ready to load |
//! | `RDA_DA_Porucha` | in | BOOL | `RDA_LOGO` | generator failed to start |
//! | `RDA_DA_U` | in | REAL V | `RDA_LOGO` | generator terminal voltage |
//! | `RDA_FV1_Prepetova_ochrana`, `RDA_FU1_Pretavena_pojistka` | in | BOOL | `RDA_LOGO` | surge arrester tripped, fuse blown |
//! | `RZS1_KHU1_Napeti` | in | BOOL | `RZS1_DI` | RZS busbar voltage present |
//! | `RZS1_FV1_Prepetova_ochrana`, `RZS1_FU1_Pretavena_pojistka` | in | BOOL | `RZS1_DI` | surge arrester tripped, fuse blown |
//! | `RZS1_U`, `RZS1_P_kW`, `RZS1_I_A`, `RZS1_Energie_kWh` | in | REAL | `RZS1_DI` | busbar voltage (from the generator's curve when fed by it), power, current, energy |
//! | `UZ_Napeti_RZZ`, `UZ_Napeti_RZS1` | in | BOOL | `RZS1_DI` | universal source: input from RZZ (TZ1) / backup input from RZS1 live |
//! | `UZ_K1_Zapnut`, `UZ_K2_Zapnut` | in | BOOL | `RZS1_DI` | universal source fed from RZZ / from RZS1 |
//! | `UZ_Vystup` | in | BOOL | `RZS1_DI` | signalling equipment supplied |
//! | `SZZ_P_kW` | in | REAL kW | `RZS1_DI` | power of the signalling equipment |
//! | `{D}_QF1_Zapnut` | in | BOOL | `{D}_DI` | incoming breaker QF1 closed (cable from RH1.1 / RZS) |
//! | `{D}_KHU1_Napeti` | in | BOOL | `{D}_DI` | busbar voltage present |
//! | `{D}_FV1_Prepetova_ochrana`, `{D}_FU1_Pretavena_pojistka` | in | BOOL | `{D}_DI` | surge arrester tripped, fuse blown |
//! | `{D}_U`, `{D}_P_kW`, `{D}_I_A`, `{D}_Energie_kWh` | in | REAL | `{D}_DI` | busbar voltage, power, current, energy |
//! | `RDRT_FV230`, `RDRT_FV110`, `RDRT_FV24` | in | BOOL | `RDRT_P9` | DI0–DI2: surge arresters tripped (SP 1–3) |
//! | `RDRT_G230_OK`, `RDRT_G110_OK`, `RDRT_G24_OK` | in | BOOL | `RDRT_P9` | DI3–DI5: supplies healthy (SP 4–6 invert them) |
//! | `RDRT_Rezerva_DI6` | in | BOOL | `RDRT_P9` | DI6: spare |
//! | `RDRT_Switch_ABB_OK` | in | BOOL | `RDRT_P9` | DI7: ABB switch healthy (SP 9 inverts it) |
//! | `RDRT_Switch_Korenix_Porucha`, `RDRT_Switch_Siemens_Porucha` | in | BOOL | `RDRT_P9` | DI8, DI9: switch faults (SP 8, 10) |
//! | `RDRT_Dvere_NN`, `RDRT_Dvere_VN`, `RDRT_Dvere_T1`, `RDRT_Dvere_T2` | in | BOOL | `RDRT_P6` | switchroom LV/HV and transformer chamber doors open |
//! | `{L}_OvladanyQ` | out | BOOL | `{L}_PLC` | lighting contactor KM1 coil (the FB's `OvladanyQ`) |
//! | `{L}_Dalkove` | in | BOOL | `{L}_PLC` | remote-control enable switch |
//! | `{L}_Cidlo` | in | BOOL | `{L}_PLC` | dusk sensor, TRUE = dark |
//! | `{L}_PrRele` | in | BOOL | `{L}_PLC` | lamp-circuit feedback relay |
//! | `{L}_KM1_Zapnut` | in | BOOL | `{L}_PLC` | lighting contactor closed |
//! | `{L}_Rucne_Zap` | in | BOOL | `{L}_PLC` | hard-wired 0/1 switch in 1 (manual contactor KM2) |
//! | `{L}_Dvere` | in | BOOL | `{L}_PLC` | cabinet door open |
//! | `{L}_Termostat_Min`, `{L}_Termostat_Max` | in | BOOL | `{L}_PLC` | cabinet thermostats (not modelled: FALSE) |
//! | `{L}_FV1_Prepetova_ochrana` | in | BOOL | `{L}_PLC` | surge arrester (255 V) tripped |
//! | `{L}_FU1_Pretavena_pojistka` | in | BOOL | `{L}_PLC` | lamp-circuit fuse blown (also cuts the lamps) |
//! | `{L}_Napeti` | in | BOOL | `{L}_PLC` | board supply present |
//! | `{L}_P_kW`, `{L}_I_A`, `{L}_Energie_kWh` | in | REAL | `{L}_PLC` | lamp power, phase current and energy (ABB meter) |
//! | `{L}_Svit_pct` | in | REAL % | `{L}_PLC` | light output (warm-up ramp) |
//! | `ENV_Osvetlenost_lx` | in | REAL lx | `ENV` | outdoor illuminance |
//!
//! That is 415 inputs and 24 outputs.
//!
//! # Faults ([`Fault`]) and hand operations ([`Action`])
//!
//! | Text form | Effect |
//! |---|---|
//! | `supply-loss TNS_USTI\|TNS_VALMEZ\|UTILITY\|T1\|T2` | source dead / transformer out (mains loss on T1 de-energises RZZ, not RH2) |
//! | `generator-fail-to-start` | cranks, then `RDA_DA_Porucha`; clearing restarts a held start |
//! | `stuck-closed NAME`, `stuck-open NAME` | any breaker or contactor jumps to and stays in that position |
//! | `breaker-tripped NAME` | the breaker opens by its protection; clearing recloses a manual one |
//! | `lamp-failure {L}` | lamp circuit broken: no current, `PrRele` drops |
//! | `fuse-blown NAME` | `*_FU1` indication (a lighting board's FU1 also cuts its lamps) |
//! | `surge-arrester NAME` | `*_FV1`, `*_FV110`, `RDRT_FV*` indication |
//! | `emergency-off RH2\|RZZ\|RH12\|RZS2\|RDA` | latched mushroom button: trips QF1 / cuts the RDA contactors |
//! | `door-open {L}\|RDRT_NN\|RDRT_VN\|RDRT_T1\|RDRT_T2` | door contact |
//! | `supply-unit-fault {B}_G110.2\|RDRT_G230\|RDRT_G110\|RDRT_G24` | supply-healthy contact drops |
//! | `network-switch-fault RDRT_ABB\|RDRT_KORENIX\|RDRT_SIEMENS` | switch fault contact |
//! | `module-pulled MODULE` | inputs invalid, outputs de-energised |
//! | `communication-lost MODULE` | inputs invalid, the field keeps the last outputs |
//!
//! Hand operations: [`Action::SetSelector`] (SA1 of RH2/RZZ/RDA, `Dalkove` of the
//! lighting boards), [`Action::SetManualSwitch`] (0/1 switch of a lighting board),
//! [`Action::Close`]/[`Action::Open`] (manual breakers at once; QF1 by its door pushbutton,
//! only in local), [`Action::SetIlluminance`].
//!
//! # Left out
//!
//! - Load flow: voltages are nominal (or the generator's curve), each load draws its
//!   constant rating and currents are derived from power and voltage; no voltage drop,
//!   no overload, no protection settings or selectivity (a breaker trips only by fault
//!   injection or its coils).
//! - The RS602 6 kV by-pass, the TZ1 signalling supply and RZZ/RZS1 backup of the
//!   signalling equipment, the RH1.2 and RZS2 boards and the DT building.
//! - Cabinet temperature (thermostat inputs are constant FALSE), heaters and fans.
//! - Loss of a PLC's own supply when its board is dead: the PLC is assumed to keep running
//!   (model it with `module-pulled`).
//! - Generator trips while running, frequency, fuel; lamp ageing and single-lamp failures.
//! - Control logic of any kind: RDA transfer, LOGO! breaker logic, the lighting FB.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]

mod core;
mod devices;
pub mod lab;
pub mod registry;
pub mod sorter;
pub mod sun;
mod topology;
pub mod vsetin;

pub use crate::core::{
    signal_table_markdown, ConsoleOperation, Direction, Module, Plant, PlantError, Reading,
    SerialPortInfo, SignalInfo, SimTime, StatusLine, Value, ValueKind,
};
pub use crate::devices::{GeneratorConfig, GeneratorState};
pub use crate::topology::{
    BusState, LinkState, SafetyEvent, SafetyKind, SourceState, TopologySnapshot,
};
pub use crate::vsetin::fault::{operation_syntax, Action, DeviceKind, Fault, OperationSyntax};
pub use crate::vsetin::{lighting_boards, StationConfig, SwitchingDevice, Transfer, VsetinPlant};
