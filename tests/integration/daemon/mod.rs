mod cli;
mod navigate_goal;
mod operate;
mod pose;
mod record;
