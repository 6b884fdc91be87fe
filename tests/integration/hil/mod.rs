mod compliance;
mod delay;
mod determinism;
mod failsafe;
mod gaits;
mod keyed_gateway;
