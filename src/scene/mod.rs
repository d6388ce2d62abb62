//! The blade-spreading scene: from one design point to every number the deck needs.
//!
//! The physics lives here, typed and unit-tested; the template only lays the numbers out.

pub mod params;
