//! snaked as a ROS 2 node (issue 47, in progress): ROS 2's own messages
//! ([`msg`]), published from what the loop hands the recorder, never from the loop.

pub mod bridge;
pub mod msg;
#[cfg(test)]
mod msg_tests;
