mod layout;
mod live;
mod no_alloc;
mod python;
mod writer;
