//! What several of the host's tests share.

pub mod stand_in;
pub mod tanks;
