mod control_cycles;
mod controllers;
mod gaits;
