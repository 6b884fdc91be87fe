mod codec;
mod udp_alloc;
