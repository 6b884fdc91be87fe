mod controller_commands;
mod controllers;
mod lifecycle;
mod methods;
mod navigate;
mod protocol;
mod real;
mod snakectl;
