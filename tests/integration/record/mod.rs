mod accept;
mod layout;
mod live;
mod no_alloc;
mod python;
mod recover;
mod writer;
