mod integrity;
mod sim_alloc;
mod udp;
