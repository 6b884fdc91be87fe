mod cli;
mod operate;
mod pose;
mod record;
