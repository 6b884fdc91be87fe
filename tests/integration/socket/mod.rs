mod controllers;
mod lifecycle;
mod methods;
mod protocol;
mod snakectl;
