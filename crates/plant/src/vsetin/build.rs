//! Construction of the station: buses, links, devices and the signal table.

use std::time::Duration;

use super::{
    lighting_boards, Board, BreakerDev, Coil, Contact, ContactKind, ContactorDev, Lighting, Module,
    Out, RelayDev, Sense, Sig, Src, SupplyRef, VsetinPlant,
};
use crate::core::{Direction, SignalInfo, ValueKind};
use crate::devices::{Breaker, Delayed};

impl VsetinPlant {
    fn module(&mut self, name: &str) -> usize {
        if let Some(i) = self.modules.iter().position(|m| m.name == name) {
            return i;
        }
        self.modules.push(Module {
            name: name.to_string(),
            present: true,
            linked: true,
        });
        self.modules.len() - 1
    }

    fn input(&mut self, name: &str, module: usize, desc: &str, src: Src) {
        let (kind, unit) = match src {
            Src::BusVoltage(..) | Src::GenVoltage => (ValueKind::Real, "V"),
            Src::BoardPower(_) | Src::LightPower(_) => (ValueKind::Real, "kW"),
            Src::BoardCurrent(_) | Src::LightCurrent(_) => (ValueKind::Real, "A"),
            Src::BoardEnergy(_) | Src::LightEnergy(_) => (ValueKind::Real, "kWh"),
            Src::LightOutput(_) => (ValueKind::Real, "%"),
            Src::Illuminance => (ValueKind::Real, "lx"),
            _ => (ValueKind::Bool, ""),
        };
        self.push_sig(
            name,
            Direction::Input,
            kind,
            unit,
            module,
            desc,
            Sig::In(src),
        );
    }

    fn output(&mut self, name: &str, module: usize, desc: &str) -> usize {
        self.outs.push(Out {
            value: false,
            module,
        });
        let slot = self.outs.len() - 1;
        self.push_sig(
            name,
            Direction::Output,
            ValueKind::Bool,
            "",
            module,
            desc,
            Sig::Out(slot),
        );
        slot
    }

    #[allow(clippy::too_many_arguments)]
    fn push_sig(
        &mut self,
        name: &str,
        direction: Direction,
        kind: ValueKind,
        unit: &'static str,
        module: usize,
        desc: &str,
        sig: Sig,
    ) {
        self.sig_module.push(module);
        let module = self
            .modules
            .get(module)
            .map(|m| m.name.clone())
            .unwrap_or_default();
        self.index.insert(name.to_string(), self.infos.len());
        self.infos.push(SignalInfo {
            name: name.to_string(),
            direction,
            kind,
            module,
            unit,
            description: desc.to_string(),
        });
        self.sigs.push(sig);
    }

    fn breaker(&mut self, name: &str, closed: bool, link: Option<usize>) -> usize {
        self.breakers.push(BreakerDev {
            name: name.to_string(),
            dev: Breaker::new(
                closed,
                self.cfg.breaker_close_time,
                self.cfg.breaker_open_time,
            ),
            link,
            close_out: None,
            trip_out: None,
            board: None,
            tripped: false,
            both_coils: false,
            interlock: None,
        });
        self.breakers.len() - 1
    }

    fn contactor(&mut self, name: &str, link: Option<usize>, coil: Coil) -> usize {
        self.contactors.push(ContactorDev {
            name: name.to_string(),
            dev: Delayed::new(false, self.cfg.contactor_pickup, self.cfg.contactor_dropout),
            link,
            coil,
            estop_board: None,
        });
        self.contactors.len() - 1
    }

    fn relay(&mut self, sense: Sense) -> usize {
        self.relays.push(RelayDev {
            dev: Delayed::new(false, self.cfg.relay_time, self.cfg.relay_time),
            sense,
        });
        self.relays.len() - 1
    }

    fn contact(&mut self, name: &str, kind: ContactKind) -> usize {
        self.contacts.push(Contact {
            name: name.to_string(),
            kind,
            active: false,
        });
        self.contacts.len() - 1
    }

    fn board(&mut self, name: &str, bus: usize, base_kw: f64, has_estop: bool) -> usize {
        self.boards.push(Board {
            name: name.to_string(),
            remote: true,
            estop: false,
            has_estop,
            bus,
            base_kw,
            live_ns: 0,
        });
        self.boards.len() - 1
    }

    pub(super) fn build(&mut self) {
        // Buses and sources (grid sources first: they name a bus's supply when paralleled).
        let n = &mut self.net;
        let b_usti = n.add_bus("TNS_USTI");
        let b_valmez = n.add_bus("TNS_VALMEZ");
        let b_r6 = n.add_bus("R6");
        let b_t1 = n.add_bus("T1_LV");
        let b_t2 = n.add_bus("T2_LV");
        let b_rzz = n.add_bus("RZZ");
        let b_rzza = n.add_bus("RZZ_A");
        let b_rzz_v1 = n.add_bus("RZZ_V1");
        let b_rh2 = n.add_bus("RH2");
        let b_rh2_v1 = n.add_bus("RH2_V1");
        let b_util = n.add_bus("UTILITY");
        let b_rh11 = n.add_bus("RH11");
        let b_rh11ab = n.add_bus("RH11_AB");
        let b_rzs = n.add_bus("RZS");
        let b_da = n.add_bus("DA");
        // The switchroom's cable ends and the transformers' 6 kV side, between which the
        // by-pass RS602 closes (railway spec 2.2; the model's choice of what it bridges).
        let b_r6_usti = n.add_bus("R6_USTI");
        let b_r6_valmez = n.add_bus("R6_VALMEZ");
        let b_r6_t = n.add_bus("R6_T");
        let b_rh12 = n.add_bus("RH12");
        let b_rh12_v1 = n.add_bus("RH12_V1");
        let b_rzs2 = n.add_bus("RZS2");
        let b_rzs2_v1 = n.add_bus("RZS2_V1");
        let b_rhdt = n.add_bus("RHDT");
        let b_rzsdt = n.add_bus("RZSDT");
        let b_szz = n.add_bus("SZZ");
        let s_usti = n.add_source("TNS_USTI", b_usti, "grid");
        let s_valmez = n.add_source("TNS_VALMEZ", b_valmez, "grid");
        let s_util = n.add_source("UTILITY", b_util, "grid");
        self.da_source = n.add_source("DA", b_da, "diesel");
        n.add_link("LINE_USTI", b_usti, b_r6_usti);
        n.add_link("LINE_VALMEZ", b_valmez, b_r6_valmez);
        let l_q1 = n.add_link("R6_Q1", b_r6_usti, b_r6);
        let l_q2 = n.add_link("R6_Q2", b_r6_valmez, b_r6);
        let l_q3 = n.add_link("R6_Q3", b_r6, b_r6_t);
        let l_rs602 = n.add_link("RS602", b_r6_usti, b_r6_t);
        let l_t1 = n.add_link("T1", b_r6_t, b_t1);
        let l_t2 = n.add_link("T2", b_r6_t, b_t2);
        n.add_link("TI_RZZA", b_rzz, b_rzza);
        n.add_link("TI_RH11", b_rh11, b_rh11ab);
        for (name, r) in [
            ("TNS_USTI", SupplyRef::Source(s_usti)),
            ("TNS_VALMEZ", SupplyRef::Source(s_valmez)),
            ("UTILITY", SupplyRef::Source(s_util)),
            ("T1", SupplyRef::Link(l_t1)),
            ("T2", SupplyRef::Link(l_t2)),
        ] {
            self.supplies.insert(name.to_string(), (r, false));
        }
        let r6_q1 = self.breaker("R6_Q1", true, Some(l_q1));
        let r6_q2 = self.breaker("R6_Q2", true, Some(l_q2));
        let r6_q3 = self.breaker("R6_Q3", true, Some(l_q3));
        let rs602 = self.breaker("RS602", false, Some(l_rs602));
        for (a, b) in [(rs602, r6_q3), (r6_q3, rs602)] {
            if let Some(x) = self.breakers.get_mut(a) {
                x.interlock = Some(b);
            }
        }

        // RH2 (fed from T2) and RZZ (fed from T1): LOGO! boards of the same pattern.
        let rh2_feeders = self.logo_board("RH2", b_t2, b_rh2, b_rh2_v1, 5.0);
        self.logo_board("RZZ", b_t1, b_rzz, b_rzz_v1, 8.0);

        // RH1.1: main board on the distribution connection.
        let m = self.module("RH11_DI");
        let l = self.net.add_link("RH11_QF1", b_util, b_rh11);
        let qf = self.breaker("RH11_QF1", true, Some(l));
        let bd = self.board("RH11", b_rh11, 15.0, false);
        let khu = self.relay(Sense::Bus(b_util));
        let fv = self.contact("RH11_FV1", ContactKind::Arrester);
        let fu = self.contact("RH11_FU1", ContactKind::Fuse);
        self.input(
            "RH11_QF1_Zapnut",
            m,
            "main breaker QF1 (utility feed) closed",
            Src::BreakerClosed(qf),
        );
        self.input(
            "RH11_KHU1_Napeti_sit",
            m,
            "utility voltage present (relay KHU1)",
            Src::Relay(khu),
        );
        self.input(
            "RH11_FV1_Prepetova_ochrana",
            m,
            "surge arrester FV1 tripped",
            Src::Contact(fv, true),
        );
        self.input(
            "RH11_FU1_Pretavena_pojistka",
            m,
            "fuse FU1 blown",
            Src::Contact(fu, true),
        );
        self.board_meter("RH11", m, b_rh11, bd);
        self.input(
            "R6_U",
            m,
            "6 kV switchroom voltage",
            Src::BusVoltage(b_r6, 6000.0),
        );
        self.input(
            "R6_T_U",
            m,
            "6 kV voltage at the transformers T1/T2 (through R6 or the by-pass RS602)",
            Src::BusVoltage(b_r6_t, 6000.0),
        );
        for (sig, dev, desc) in [
            (
                "R6_Q1_Zapnut",
                r6_q1,
                "R6 incoming cubicle Q1 (line from TNS Ústí) closed",
            ),
            (
                "R6_Q2_Zapnut",
                r6_q2,
                "R6 incoming cubicle Q2 (line from TNS Valašské Meziříčí) closed",
            ),
            (
                "R6_Q3_Zapnut",
                r6_q3,
                "R6 transformer feeder Q3 (to T1/T2) closed",
            ),
            (
                "RS602_Zapnut",
                rs602,
                "by-pass disconnector box RS602 closed (R6 by-passed)",
            ),
        ] {
            self.input(sig, m, desc, Src::BreakerClosed(dev));
        }
        self.board("RH11_AB", b_rh11ab, 3.0, false);
        self.board("RZZ_A", b_rzza, 3.0, false);

        // RH1.2: the main board's second section, a LOGO! board of the RH2 pattern fed from
        // RH1.1 (railway spec 3.1; its feed and load are the model's choice).
        self.logo_board("RH12", b_rh11, b_rh12, b_rh12_v1, 6.0);

        // RDA: automatic transfer between RH1.1 (mains) and the diesel generator onto RZS.
        let m = self.module("RDA_LOGO");
        let bd = self.board("RDA", b_rzs, 0.0, true);
        let l1 = self.net.add_link("RDA_KM1", b_rh11, b_rzs);
        let l2 = self.net.add_link("RDA_KM2", b_da, b_rzs);
        let o1 = self.output(
            "RDA_KM1_Zap",
            m,
            "coil of contactor KM1 (supply from RH1.1, mains)",
        );
        let o2 = self.output(
            "RDA_KM2_Zap",
            m,
            "coil of contactor KM2 (supply from the diesel generator)",
        );
        let os = self.output(
            "RDA_DA_Start",
            m,
            "generator start/run request (level; removing it stops after cool-down)",
        );
        let k1 = self.contactor("RDA_KM1", Some(l1), Coil::Output(o1));
        let k2 = self.contactor("RDA_KM2", Some(l2), Coil::Output(o2));
        for k in [k1, k2] {
            if let Some(c) = self.contactors.get_mut(k) {
                c.estop_board = Some(bd);
            }
        }
        let r1 = self.relay(Sense::Bus(b_rh11));
        let r2 = self.relay(Sense::Generator);
        let r3 = self.relay(Sense::Bus(b_rzs));
        let fv = self.contact("RDA_FV1", ContactKind::Arrester);
        let fu = self.contact("RDA_FU1", ContactKind::Fuse);
        self.gen_start = Some(os);
        self.input(
            "RDA_KM1_Zapnut",
            m,
            "KM1 (mains) closed, auxiliary contact",
            Src::ContactorClosed(k1),
        );
        self.input(
            "RDA_KM2_Zapnut",
            m,
            "KM2 (diesel) closed, auxiliary contact",
            Src::ContactorClosed(k2),
        );
        self.input(
            "RDA_KHU1_Napeti_sit",
            m,
            "mains voltage present on the RH1.1 side (relay KHU1)",
            Src::Relay(r1),
        );
        self.input(
            "RDA_KHU2_Napeti_DA",
            m,
            "generator voltage >= 90 % (relay KHU2)",
            Src::Relay(r2),
        );
        self.input(
            "RDA_KHU3_Napeti_RZS",
            m,
            "RZS busbar voltage present (relay KHU3)",
            Src::Relay(r3),
        );
        self.input(
            "RDA_SA1_Mistne",
            m,
            "selector SA1 in local",
            Src::Selector(bd, false),
        );
        self.input(
            "RDA_SA1_Dalkove",
            m,
            "selector SA1 in remote",
            Src::Selector(bd, true),
        );
        self.input(
            "RDA_KHVRDA_Havarijni_vypnuti",
            m,
            "emergency off of RDA (cuts both contactor coils)",
            Src::Estop(bd),
        );
        self.input(
            "RDA_DA_Bezi",
            m,
            "generator engine running",
            Src::GenRunning,
        );
        self.input(
            "RDA_DA_Pripraven",
            m,
            "generator voltage settled, ready to load",
            Src::GenReady,
        );
        self.input(
            "RDA_DA_Porucha",
            m,
            "generator fault (failed to start)",
            Src::GenFault,
        );
        self.input("RDA_DA_U", m, "generator terminal voltage", Src::GenVoltage);
        self.input(
            "RDA_FV1_Prepetova_ochrana",
            m,
            "surge arrester FV1 tripped",
            Src::Contact(fv, true),
        );
        self.input(
            "RDA_FU1_Pretavena_pojistka",
            m,
            "fuse FU1 blown",
            Src::Contact(fu, true),
        );

        // RZS1: secured-network board.
        let m = self.module("RZS1_DI");
        let bd = self.board("RZS1", b_rzs, 10.0, false);
        let r = self.relay(Sense::Bus(b_rzs));
        let fv = self.contact("RZS1_FV1", ContactKind::Arrester);
        let fu = self.contact("RZS1_FU1", ContactKind::Fuse);
        self.input(
            "RZS1_KHU1_Napeti",
            m,
            "busbar voltage present (relay KHU1)",
            Src::Relay(r),
        );
        self.input(
            "RZS1_FV1_Prepetova_ochrana",
            m,
            "surge arrester FV1 tripped",
            Src::Contact(fv, true),
        );
        self.input(
            "RZS1_FU1_Pretavena_pojistka",
            m,
            "fuse FU1 blown",
            Src::Contact(fu, true),
        );
        self.board_meter("RZS1", m, b_rzs, bd);

        // The signalling equipment's universal source (railway spec 2.2): fed from RZZ
        // (whose transformer T1 is the thesis's TZ1 6/0.4 kV from the 6 kV level), backed
        // up from RZS1; its changeover prefers RZZ and never closes both inputs. Its state
        // contacts are wired to RZS1's DI module (the model's choice).
        let l_k1 = self.net.add_link("UZ_K1", b_rzz, b_szz);
        let l_k2 = self.net.add_link("UZ_K2", b_rzs, b_szz);
        let khu_rzz = self.relay(Sense::Bus(b_rzz));
        let khu_rzs = self.relay(Sense::Bus(b_rzs));
        let khu_szz = self.relay(Sense::Bus(b_szz));
        let k1 = self.contactor(
            "UZ_K1",
            Some(l_k1),
            Coil::Changeover {
                own: khu_rzz,
                yields_to: None,
                interlock: usize::MAX,
            },
        );
        let k2 = self.contactor(
            "UZ_K2",
            Some(l_k2),
            Coil::Changeover {
                own: khu_rzs,
                yields_to: Some(khu_rzz),
                interlock: k1,
            },
        );
        if let Some(c) = self.contactors.get_mut(k1) {
            c.coil = Coil::Changeover {
                own: khu_rzz,
                yields_to: None,
                interlock: k2,
            };
        }
        let uz = self.board("SZZ", b_szz, 4.0, false);
        for (sig, desc, src) in [
            (
                "UZ_Napeti_RZZ",
                "universal source: input from RZZ (TZ1) live",
                Src::Relay(khu_rzz),
            ),
            (
                "UZ_Napeti_RZS1",
                "universal source: backup input from RZS1 live",
                Src::Relay(khu_rzs),
            ),
            (
                "UZ_K1_Zapnut",
                "universal source fed from RZZ (contactor K1 closed)",
                Src::ContactorClosed(k1),
            ),
            (
                "UZ_K2_Zapnut",
                "universal source fed from RZS1, backup (contactor K2 closed)",
                Src::ContactorClosed(k2),
            ),
            (
                "UZ_Vystup",
                "signalling equipment supplied (universal source output live)",
                Src::Relay(khu_szz),
            ),
        ] {
            self.input(sig, m, desc, src);
        }
        self.input(
            "SZZ_P_kW",
            m,
            "active power of the signalling equipment",
            Src::BoardPower(uz),
        );

        // RZS2: the secured network's second board, a LOGO! board of the RH2 pattern fed
        // from RZS (railway spec 3.1; feed and load the model's choice).
        self.logo_board("RZS2", b_rzs, b_rzs2, b_rzs2_v1, 4.0);

        // DT: the RH and RZS boards of the transport terminal with their S7-1500s (railway
        // spec 2.1, 3.1), fed over cables from RH1.1 and RZS (the model's choice).
        self.dt_board("RHDT", b_rh11, b_rhdt, 20.0, "RH1.1");
        self.dt_board("RZSDT", b_rzs, b_rzsdt, 6.0, "RZS (RZS1)");

        // RDRT: TC700 module p9 (DI0..DI9) and the door contacts on module p6.
        let m = self.module("RDRT_P9");
        for (sig, dev, kind, active_true, desc) in [
            (
                "RDRT_FV230",
                "RDRT_FV230",
                ContactKind::Arrester,
                true,
                "DI0: surge arrester FV230 tripped",
            ),
            (
                "RDRT_FV110",
                "RDRT_FV110",
                ContactKind::Arrester,
                true,
                "DI1: surge arrester FV110 tripped",
            ),
            (
                "RDRT_FV24",
                "RDRT_FV24",
                ContactKind::Arrester,
                true,
                "DI2: surge arrester FV24 tripped",
            ),
            (
                "RDRT_G230_OK",
                "RDRT_G230",
                ContactKind::SupplyUnit,
                false,
                "DI3: supply G230 healthy (SP 4 inverts it)",
            ),
            (
                "RDRT_G110_OK",
                "RDRT_G110",
                ContactKind::SupplyUnit,
                false,
                "DI4: supply G110 healthy (SP 5 inverts it)",
            ),
            (
                "RDRT_G24_OK",
                "RDRT_G24",
                ContactKind::SupplyUnit,
                false,
                "DI5: supply G24 healthy (SP 6 inverts it)",
            ),
            (
                "RDRT_Switch_ABB_OK",
                "RDRT_ABB",
                ContactKind::NetSwitch,
                false,
                "DI7: ABB switch healthy (SP 9 inverts it)",
            ),
            (
                "RDRT_Switch_Korenix_Porucha",
                "RDRT_KORENIX",
                ContactKind::NetSwitch,
                true,
                "DI8: Korenix switch fault",
            ),
            (
                "RDRT_Switch_Siemens_Porucha",
                "RDRT_SIEMENS",
                ContactKind::NetSwitch,
                true,
                "DI9: Siemens switch fault",
            ),
        ] {
            let c = self.contact(dev, kind);
            self.input(sig, m, desc, Src::Contact(c, active_true));
        }
        self.input("RDRT_Rezerva_DI6", m, "DI6: spare", Src::Const(false));
        let m = self.module("RDRT_P6");
        for (d, desc) in [
            ("NN", "LV switchroom door open"),
            ("VN", "HV switchroom door open"),
            ("T1", "transformer chamber T1 door open"),
            ("T2", "transformer chamber T2 door open"),
        ] {
            let c = self.contact(&format!("RDRT_{d}"), ContactKind::Door);
            self.input(&format!("RDRT_Dvere_{d}"), m, desc, Src::Contact(c, true));
        }

        // Lighting: towers 1-3 on RH2 FA1.1, 4-6 on FA1.2, 7-9 on FA1.3, 10-12 on FA1.4,
        // the OŘ area on FA1.5.
        for (i, name) in lighting_boards().into_iter().enumerate() {
            let feeder = rh2_feeders.get((i / 3).min(4)).copied().unwrap_or(b_rh2_v1);
            let power = if name == "OR" {
                self.cfg.or_power_kw
            } else {
                self.cfg.tower_power_kw
            };
            self.lighting_board(&name, feeder, power);
        }
        let m = self.module("ENV");
        self.input(
            "ENV_Osvetlenost_lx",
            m,
            "outdoor illuminance (sun model or forced)",
            Src::Illuminance,
        );
    }

    /// A board's meter on its module `m`: `{p}_U` (busbar voltage), `{p}_P_kW`, `{p}_I_A`
    /// and `{p}_Energie_kWh` of the board `bd`'s own load.
    fn board_meter(&mut self, p: &str, m: usize, bus: usize, bd: usize) {
        self.input(
            &format!("{p}_U"),
            m,
            "busbar voltage",
            Src::BusVoltage(bus, 400.0),
        );
        self.input(
            &format!("{p}_P_kW"),
            m,
            "active power of the board's own load",
            Src::BoardPower(bd),
        );
        self.input(
            &format!("{p}_I_A"),
            m,
            "phase current (three-phase, from power and voltage)",
            Src::BoardCurrent(bd),
        );
        self.input(
            &format!("{p}_Energie_kWh"),
            m,
            "energy meter",
            Src::BoardEnergy(bd),
        );
    }

    /// A board in DT with its S7-1500's DI module `{p}_DI`: an incoming breaker QF1 (by
    /// hand) on a cable from `from`, voltage relay, surge arrester, fuse and meter.
    fn dt_board(&mut self, p: &str, b_from: usize, b_bus: usize, base_kw: f64, from: &str) {
        let m = self.module(&format!("{p}_DI"));
        let l = self.net.add_link(&format!("{p}_QF1"), b_from, b_bus);
        let qf = self.breaker(&format!("{p}_QF1"), true, Some(l));
        let bd = self.board(p, b_bus, base_kw, false);
        let khu = self.relay(Sense::Bus(b_bus));
        let fv = self.contact(&format!("{p}_FV1"), ContactKind::Arrester);
        let fu = self.contact(&format!("{p}_FU1"), ContactKind::Fuse);
        self.input(
            &format!("{p}_QF1_Zapnut"),
            m,
            &format!("incoming breaker QF1 (cable from {from}) closed"),
            Src::BreakerClosed(qf),
        );
        self.input(
            &format!("{p}_KHU1_Napeti"),
            m,
            "busbar voltage present (relay KHU1)",
            Src::Relay(khu),
        );
        self.input(
            &format!("{p}_FV1_Prepetova_ochrana"),
            m,
            "surge arrester FV1 tripped",
            Src::Contact(fv, true),
        );
        self.input(
            &format!("{p}_FU1_Pretavena_pojistka"),
            m,
            "fuse FU1 blown",
            Src::Contact(fu, true),
        );
        self.board_meter(p, m, b_bus, bd);
    }

    /// RH2 / RZZ pattern (also RH1.2 and RZS2); returns the five feeder buses of
    /// FA1.1..FA1.5.
    fn logo_board(
        &mut self,
        p: &str,
        b_in: usize,
        b_bus: usize,
        b_v1: usize,
        base_kw: f64,
    ) -> Vec<usize> {
        let m = self.module(&format!("{p}_LOGO"));
        let bd = self.board(p, b_bus, base_kw, true);
        let l = self.net.add_link(&format!("{p}_QF1"), b_in, b_bus);
        let qf = self.breaker(
            &format!("{p}_QF1"),
            self.cfg.feeders_initially_closed,
            Some(l),
        );
        let o_off = self.output(
            &format!("{p}_QF1_Vyp"),
            m,
            "trip coil of feeder breaker QF1 (DO 'QF1 off')",
        );
        let o_on = self.output(
            &format!("{p}_QF1_Zap"),
            m,
            "close coil of feeder breaker QF1 (DO 'QF1 on', rising edge closes)",
        );
        if let Some(b) = self.breakers.get_mut(qf) {
            b.close_out = Some(o_on);
            b.trip_out = Some(o_off);
            b.board = Some(bd);
        }
        let l = self.net.add_link(&format!("{p}_FA1"), b_bus, b_v1);
        let fa1 = self.breaker(&format!("{p}_FA1"), true, Some(l));
        self.input(
            &format!("{p}_V1_FA1_Zapnut"),
            m,
            "breaker FA1 closed",
            Src::BreakerClosed(fa1),
        );
        let mut feeders = Vec::new();
        for k in 1..=5 {
            let fb = self.net.add_bus(&format!("{p}_F{k}"));
            let l = self.net.add_link(&format!("{p}_FA1.{k}"), b_v1, fb);
            let b = self.breaker(&format!("{p}_FA1.{k}"), true, Some(l));
            self.input(
                &format!("{p}_V1_FA1.{k}"),
                m,
                &format!("breaker FA1.{k} closed"),
                Src::BreakerClosed(b),
            );
            feeders.push(fb);
        }
        for k in 0..=2 {
            let b = self.breaker(&format!("{p}_FA110.{k}"), true, None);
            self.input(
                &format!("{p}_P1_FA110.{k}"),
                m,
                &format!("breaker FA110.{k} (110 V DC) closed"),
                Src::BreakerClosed(b),
            );
        }
        let khu1 = self.relay(Sense::Bus(b_in));
        let khu3 = self.relay(Sense::Bus(b_bus));
        self.input(
            &format!("{p}_P1_KHU1_Napeti_na_privodu"),
            m,
            "voltage present on the incoming feeder, upstream of QF1 (relay KHU1)",
            Src::Relay(khu1),
        );
        self.input(
            &format!("{p}_P1_KHU3_Napeti_na_pripojeni"),
            m,
            "voltage present on the busbar, downstream of QF1 (relay KHU3)",
            Src::Relay(khu3),
        );
        self.input(
            &format!("{p}_P1_SA1_Mistne"),
            m,
            "selector SA1 in local",
            Src::Selector(bd, false),
        );
        self.input(
            &format!("{p}_P1_SA1_Dalkove"),
            m,
            "selector SA1 in remote",
            Src::Selector(bd, true),
        );
        let fu = self.contact(&format!("{p}_FU1"), ContactKind::Fuse);
        let fv = self.contact(&format!("{p}_FV1"), ContactKind::Arrester);
        let fv110 = self.contact(&format!("{p}_FV110"), ContactKind::Arrester);
        let g = self.contact(&format!("{p}_G110.2"), ContactKind::SupplyUnit);
        self.input(
            &format!("{p}_P1_FU1_Pretavena_pojistka"),
            m,
            "fuse FU1 blown",
            Src::Contact(fu, true),
        );
        self.input(
            &format!("{p}_P1_FV1_Prepetova_ochrana"),
            m,
            "surge arrester FV1 tripped",
            Src::Contact(fv, true),
        );
        self.input(
            &format!("{p}_P1_KHV{p}_Havarijni_vypnuti"),
            m,
            "emergency off pressed",
            Src::Estop(bd),
        );
        self.input(
            &format!("{p}_P1_FV110_Prepetova_ochrana"),
            m,
            "surge arrester FV110 (110 V) tripped",
            Src::Contact(fv110, true),
        );
        self.input(
            &format!("{p}_P1_G110.2_Napeti_zdroje"),
            m,
            "voltage of the 110 V source G110.2 present",
            Src::Contact(g, false),
        );
        for k in 1..=14 {
            self.input(
                &format!("{p}_RezervaVstup{k}"),
                m,
                "spare input",
                Src::Const(false),
            );
        }
        self.input(
            &format!("{p}_QF1_Zapnut"),
            m,
            "feeder breaker QF1 closed (auxiliary contact; not in the thesis tag list)",
            Src::BreakerClosed(qf),
        );
        self.board_meter(p, m, b_bus, bd);
        feeders
    }

    fn lighting_board(&mut self, p: &str, feeder: usize, power_kw: f64) {
        let m = self.module(&format!("{p}_PLC"));
        let bus = self.net.add_bus(p);
        self.net.add_link(&format!("{p}_CABLE"), feeder, bus);
        let o = self.output(
            &format!("{p}_OvladanyQ"),
            m,
            "lighting contactor KM1 coil (the FB's OvladanyQ)",
        );
        let li = self.lights.len();
        let km = self.contactor(&format!("{p}_KM1"), None, Coil::Output(o));
        let km_manual = self.contactor(&format!("{p}_KM2"), None, Coil::ManualSwitch(li));
        let fuse = self.contact(&format!("{p}_FU1"), ContactKind::Fuse);
        let fv = self.contact(&format!("{p}_FV1"), ContactKind::Arrester);
        let door = self.contact(p, ContactKind::Door);
        let khu = self.relay(Sense::Bus(bus));
        self.lights.push(Lighting {
            name: p.to_string(),
            bus,
            km,
            km_manual,
            fuse,
            manual_switch: false,
            remote: true,
            lamp_failed: false,
            feedback: Delayed::new(false, self.cfg.feedback_pickup, Duration::ZERO),
            energised_since: None,
            power_kw,
            on_ns: 0,
            dark: false,
            dark_next: None,
        });
        self.input(
            &format!("{p}_Dalkove"),
            m,
            "remote-control enable switch (TRUE = DDTS may control)",
            Src::LightRemote(li),
        );
        self.input(
            &format!("{p}_Cidlo"),
            m,
            "dusk sensor (TRUE = outdoor light insufficient)",
            Src::LightDusk(li),
        );
        self.input(
            &format!("{p}_PrRele"),
            m,
            "lamp-circuit feedback relay (TRUE = circuit energised and drawing current)",
            Src::LightFeedback(li),
        );
        self.input(
            &format!("{p}_KM1_Zapnut"),
            m,
            "lighting contactor KM1 closed",
            Src::ContactorClosed(km),
        );
        self.input(
            &format!("{p}_Rucne_Zap"),
            m,
            "hard-wired 0/1 switch in position 1 (manual contactor KM2)",
            Src::LightManual(li),
        );
        self.input(
            &format!("{p}_Dvere"),
            m,
            "cabinet door open (door limit switch)",
            Src::Contact(door, true),
        );
        self.input(
            &format!("{p}_Termostat_Min"),
            m,
            "cabinet below minimum temperature (not modelled: FALSE)",
            Src::Const(false),
        );
        self.input(
            &format!("{p}_Termostat_Max"),
            m,
            "cabinet above maximum temperature (not modelled: FALSE)",
            Src::Const(false),
        );
        self.input(
            &format!("{p}_FV1_Prepetova_ochrana"),
            m,
            "surge arrester FV1 (255 V) tripped",
            Src::Contact(fv, true),
        );
        self.input(
            &format!("{p}_FU1_Pretavena_pojistka"),
            m,
            "lamp-circuit fuse FU1 blown",
            Src::Contact(fuse, true),
        );
        self.input(
            &format!("{p}_Napeti"),
            m,
            "board supply voltage present (relay KHU1)",
            Src::Relay(khu),
        );
        self.input(
            &format!("{p}_P_kW"),
            m,
            "active power of the lamps (ABB meter)",
            Src::LightPower(li),
        );
        self.input(
            &format!("{p}_I_A"),
            m,
            "phase current (three-phase, from power and voltage)",
            Src::LightCurrent(li),
        );
        self.input(
            &format!("{p}_Energie_kWh"),
            m,
            "energy of the lamps (ABB meter)",
            Src::LightEnergy(li),
        );
        self.input(
            &format!("{p}_Svit_pct"),
            m,
            "light output of the lamps, % (warm-up ramp)",
            Src::LightOutput(li),
        );
    }
}
