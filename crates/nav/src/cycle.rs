//! Ranging cycles as data (Gill 2013, §2.3.2): a table of 2 s slots, each naming what is broadcast
//! (a ship or buoy state, the fleet-leader message, or silence); presets MSBL, HBL Short and
//! HBL Long exactly as Table 1; user cycles from TOML; and the assignment of ship slots to the
//! port/starboard modems for each navigation configuration (invented: docs/models.md#gill-cycles).

use crate::codec::{Header, MODEM_BUOY, MODEM_SHIP_PORT, MODEM_SHIP_STARBOARD};
use crate::surface::{Side, StateKind};
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// What one slot carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SlotContent {
    ShipEast,
    ShipNorth,
    ShipSpeed,
    ShipHeading,
    BuoyEast,
    BuoyNorth,
    /// The fleet leader's progress broadcast: not a range for a single AUV (Gill 2013, Table 1).
    FleetLeader,
    Silent,
}

/// Who transmits in a slot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Vehicle {
    Ship,
    Buoy,
}

impl SlotContent {
    /// The broadcasting vehicle and state, if the slot carries a surface-vehicle state.
    pub fn state(self) -> Option<(Vehicle, StateKind)> {
        Some(match self {
            SlotContent::ShipEast => (Vehicle::Ship, StateKind::East),
            SlotContent::ShipNorth => (Vehicle::Ship, StateKind::North),
            SlotContent::ShipSpeed => (Vehicle::Ship, StateKind::Speed),
            SlotContent::ShipHeading => (Vehicle::Ship, StateKind::Heading),
            SlotContent::BuoyEast => (Vehicle::Buoy, StateKind::East),
            SlotContent::BuoyNorth => (Vehicle::Buoy, StateKind::North),
            SlotContent::FleetLeader | SlotContent::Silent => return None,
        })
    }
    /// Mini-packet header of the slot's message.
    pub fn header(self) -> Option<Header> {
        match self {
            SlotContent::FleetLeader => Some(Header::FleetLeader),
            SlotContent::Silent => None,
            other => other.state().map(|(_, k)| match k {
                StateKind::East => Header::East,
                StateKind::North => Header::North,
                StateKind::Speed => Header::Speed,
                StateKind::Heading => Header::Heading,
            }),
        }
    }
}

/// A repeating cycle of equal slots.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cycle {
    pub name: String,
    /// Slot width (s). The WHOI mini-packet needs 2 s.
    #[serde(default = "default_slot")]
    pub slot_seconds: f64,
    pub slots: Vec<SlotContent>,
}

fn default_slot() -> f64 {
    2.0
}

#[derive(Debug, Error)]
pub enum CycleError {
    #[error("cycle '{name}': slot_seconds = {value}; must be a whole number of seconds ≥ 1 (transmissions start at the top of a second)")]
    BadSlot { name: String, value: f64 },
    #[error("cycle '{0}': slots is empty; at least one slot is needed")]
    Empty(String),
    #[error("cycle '{0}': no slot carries a ship or buoy state, so nothing would ever be ranged")]
    NoRanging(String),
    #[error("cycle file: {0}")]
    Toml(#[from] toml::de::Error),
    #[error("unknown cycle preset '{0}' (allowed: msbl, hbl_short, hbl_long)")]
    UnknownPreset(String),
}

impl Cycle {
    /// HBL Short, 16 s (Table 1).
    pub fn hbl_short() -> Self {
        use SlotContent::*;
        Cycle {
            name: "hbl_short".into(),
            slot_seconds: 2.0,
            slots: vec![ShipEast, ShipNorth, BuoyEast, ShipSpeed, ShipHeading, BuoyNorth, FleetLeader, Silent],
        }
    }
    /// HBL Long, 20 s (Table 1).
    pub fn hbl_long() -> Self {
        use SlotContent::*;
        Cycle {
            name: "hbl_long".into(),
            slot_seconds: 2.0,
            slots: vec![
                ShipEast,
                ShipNorth,
                BuoyNorth,
                ShipSpeed,
                ShipHeading,
                BuoyEast,
                FleetLeader,
                ShipEast,
                BuoyNorth,
                Silent,
            ],
        }
    }
    /// MSBL: HBL Long with the buoy slots silent (invented: docs/models.md#gill-cycles).
    pub fn msbl() -> Self {
        let mut c = Cycle::hbl_long();
        c.name = "msbl".into();
        for s in c.slots.iter_mut() {
            if matches!(s.state(), Some((Vehicle::Buoy, _))) {
                *s = SlotContent::Silent;
            }
        }
        c
    }
    pub fn preset(name: &str) -> Result<Self, CycleError> {
        match name {
            "msbl" => Ok(Cycle::msbl()),
            "hbl_short" => Ok(Cycle::hbl_short()),
            "hbl_long" => Ok(Cycle::hbl_long()),
            other => Err(CycleError::UnknownPreset(other.to_string())),
        }
    }
    /// Reads and validates a user cycle from TOML (`name`, `slot_seconds`, `slots = [...]`).
    pub fn from_toml(text: &str) -> Result<Self, CycleError> {
        let c: Cycle = toml::from_str(text)?;
        c.validate()?;
        Ok(c)
    }
    pub fn validate(&self) -> Result<(), CycleError> {
        let s = self.slot_seconds;
        if !(s.is_finite() && s >= 1.0 && s.fract() == 0.0) {
            return Err(CycleError::BadSlot { name: self.name.clone(), value: s });
        }
        if self.slots.is_empty() {
            return Err(CycleError::Empty(self.name.clone()));
        }
        if self.slots.iter().all(|s| s.state().is_none()) {
            return Err(CycleError::NoRanging(self.name.clone()));
        }
        Ok(())
    }
    pub fn period(&self) -> f64 {
        self.slot_seconds * self.slots.len() as f64
    }
    /// Slot number `k` since the start (0-based, across cycles): its content and start time.
    pub fn slot(&self, k: u64) -> (SlotContent, f64) {
        (self.slots[(k % self.slots.len() as u64) as usize], k as f64 * self.slot_seconds)
    }
}

/// The transmitting modem of a slot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Transmitter {
    Ship(Side),
    Buoy,
}

impl Transmitter {
    pub fn modem_id(self) -> u8 {
        match self {
            Transmitter::Ship(Side::Port) => MODEM_SHIP_PORT,
            Transmitter::Ship(Side::Starboard) => MODEM_SHIP_STARBOARD,
            Transmitter::Buoy => MODEM_BUOY,
        }
    }
    pub fn from_modem_id(id: u8) -> Option<Self> {
        match id {
            MODEM_SHIP_PORT => Some(Transmitter::Ship(Side::Port)),
            MODEM_SHIP_STARBOARD => Some(Transmitter::Ship(Side::Starboard)),
            MODEM_BUOY => Some(Transmitter::Buoy),
            _ => None,
        }
    }
}

/// Navigation configuration: which transponders exist (Gill 2013, §1.3–1.4 and Table 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Configuration {
    /// Two ship transponders, no buoy.
    Msbl,
    /// Buoy plus the port ship transponder only.
    HblOne,
    /// Buoy plus both ship transponders.
    HblTwo,
}

impl Configuration {
    pub fn has_buoy(self) -> bool {
        !matches!(self, Configuration::Msbl)
    }
    pub fn label(self) -> &'static str {
        match self {
            Configuration::Msbl => "MSBL",
            Configuration::HblOne => "HBL One",
            Configuration::HblTwo => "HBL Two",
        }
    }
    /// The transmitter of every slot of `cycle`: ship slots alternate port/starboard in slot
    /// order when both are fitted (HBL Two, MSBL), else port; buoy slots need a buoy.
    pub fn assign(self, cycle: &Cycle) -> Vec<Option<Transmitter>> {
        let mut ship_slots = 0usize;
        cycle
            .slots
            .iter()
            .map(|s| match s.state() {
                Some((Vehicle::Ship, _)) => {
                    let side = match (self, ship_slots % 2) {
                        (Configuration::HblOne, _) | (_, 0) => Side::Port,
                        _ => Side::Starboard,
                    };
                    ship_slots += 1;
                    Some(Transmitter::Ship(side))
                }
                Some((Vehicle::Buoy, _)) if self.has_buoy() => Some(Transmitter::Buoy),
                _ => None,
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_1_presets() {
        let s = Cycle::hbl_short();
        assert_eq!(s.period(), 16.0);
        assert_eq!(s.slot(2), (SlotContent::BuoyEast, 4.0));
        assert_eq!(s.slot(13), (SlotContent::BuoyNorth, 26.0));
        let l = Cycle::hbl_long();
        assert_eq!(l.period(), 20.0);
        let buoy: Vec<_> = l.slots.iter().filter(|c| matches!(c.state(), Some((Vehicle::Buoy, _)))).collect();
        assert_eq!(buoy, vec![&SlotContent::BuoyNorth, &SlotContent::BuoyEast, &SlotContent::BuoyNorth]);
        assert_eq!(l.slots[7], SlotContent::ShipEast);
        assert!(Cycle::msbl().slots.iter().all(|c| !matches!(c.state(), Some((Vehicle::Buoy, _)))));
        assert_eq!(SlotContent::ShipNorth.header(), Some(Header::North));
    }

    #[test]
    fn assignments() {
        let l = Cycle::hbl_long();
        let two = Configuration::HblTwo.assign(&l);
        use Transmitter::*;
        assert_eq!(two[0], Some(Ship(Side::Port)));
        assert_eq!(two[1], Some(Ship(Side::Starboard)));
        assert_eq!(two[3], Some(Ship(Side::Port)));
        assert_eq!(two[4], Some(Ship(Side::Starboard)));
        assert_eq!(two[7], Some(Ship(Side::Port)));
        assert_eq!(two[2], Some(Buoy));
        assert_eq!(two[6], None);
        let one = Configuration::HblOne.assign(&l);
        assert!(one.iter().flatten().all(|t| *t != Ship(Side::Starboard)));
        let msbl = Configuration::Msbl.assign(&l);
        assert!(msbl.iter().flatten().all(|t| *t != Buoy));
        assert_eq!(Transmitter::from_modem_id(14), Some(Ship(Side::Port)));
    }

    #[test]
    fn user_cycles_from_toml() {
        let c = Cycle::from_toml("name = 'mine'\nslots = ['ship_east', 'buoy_north', 'silent']\n").unwrap();
        assert_eq!(c.period(), 6.0);
        let e = Cycle::from_toml("name = 'x'\nslots = ['ship_east', 'buoy_up']\n").unwrap_err().to_string();
        assert!(e.contains("buoy_up") && e.contains("ship_east"), "{e}");
        let e = Cycle::from_toml("name = 'x'\nslot_seconds = 1.5\nslots = ['ship_east']\n").unwrap_err().to_string();
        assert!(e.contains("slot_seconds = 1.5"), "{e}");
        let e = Cycle::from_toml("name = 'x'\nslots = ['silent']\n").unwrap_err().to_string();
        assert!(e.contains("nothing would ever be ranged"), "{e}");
        assert!(Cycle::from_toml("name = 'x'\nslots = ['silent']\nextra = 1\n").is_err());
    }
}
