mod cli;
mod operate;
mod record;
