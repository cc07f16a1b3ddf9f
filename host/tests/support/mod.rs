//! What several of the host's tests share.

pub mod tanks;
pub mod stand_in;
