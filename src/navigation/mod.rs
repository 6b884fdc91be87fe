//! Getting across (issue 28): what the gait selector needs to pursue a direction on its
//! own. So far: knowing the body is jammed from what the daemon senses ([`stuck`]).
//! The navigator that picks and changes gaits and controllers comes next.

pub mod stuck;
