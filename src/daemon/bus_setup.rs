//! Building the loop's bus: the module network (discovery, acquire, settings) or
//! the in-process emulator.
use std::time::Duration;

use anyhow::{Context, Result, bail};

use crate::bus::Bus;
use crate::bus::hebi;
use crate::bus::udp::{self, UdpBus};
use crate::daemon::config::{BusChoice, Config, LookupBy, parse_mac};
use crate::emu::Plant;
use crate::emu::module::{EMULATOR_FIRMWARE, ModuleIdentity};
use crate::emu::plant::{JointSpacePlant, PlantConfig};
use crate::emu::sim_bus::{SimBus, SimBusConfig};
use crate::emu::world::physics::{PhysicsConfig, PhysicsPlant};
use crate::emu::world::scenario::WorldScenario;
use crate::protocol::{ControlStrategy, LookupFilter, Name, Settings};
use crate::socket::BusKind;

pub struct BuiltBus {
    pub bus: Box<dyn Bus>,
    /// Module names, head first.
    pub names: Vec<String>,
    pub kind: BusKind,
    /// The emulated world, for the recorder's 3-D scene (`None` for real modules and
    /// the joint-space plant).
    pub world: Option<crate::emu::world::WorldSpec>,
}

/// The bus the configuration asks for. Discovery gives up (with
/// [`udp::DiscoveryError::Stopped`] in the chain) as soon as `stop` is set.
pub fn build(
    cfg: &Config,
    emulated: bool,
    period_ns: u64,
    stop: &std::sync::atomic::AtomicBool,
) -> Result<BuiltBus> {
    if emulated {
        emulated_bus(cfg, period_ns)
    } else if cfg.bus.kind == BusChoice::Hebi {
        hebi_bus(cfg)
    } else {
        udp_bus(cfg, stop)
    }
}

/// The `[hebi]` spec of the group to make.
pub fn hebi_spec(h: &crate::daemon::config::HebiConfig) -> hebi::lookup::Spec {
    use hebi::lookup::Source;
    let source = if h.imitation > 0 {
        Source::Imitation(h.imitation)
    } else if !h.names.is_empty() {
        Source::Names {
            family: h.family.clone(),
            names: h.names.clone(),
        }
    } else {
        Source::Family {
            family: h.family.clone(),
            expected: h.modules,
        }
    };
    hebi::lookup::Spec {
        interfaces: h.interfaces.clone(),
        source,
        order: h.order.clone(),
        timeout: Duration::from_secs_f64(h.lookup_timeout_s),
    }
}

/// The library `[hebi]` names (or finds), loaded and checked.
pub fn hebi_library(h: &crate::daemon::config::HebiConfig) -> Result<&'static hebi::library::Api> {
    let configured = (!h.library.as_os_str().is_empty()).then_some(h.library.as_path());
    let path = hebi::library::find(configured)?;
    let api = hebi::library::load(&path)?;
    tracing::info!(path = %api.path.display(), version = %api.version_string(), "libhebi loaded");
    Ok(api)
}

/// `snaked --list-modules`: what a HEBI lookup on `[hebi] interfaces` finds, one module
/// per line, sorted by family and name.
pub fn list_hebi_modules(h: &crate::daemon::config::HebiConfig) -> Result<String> {
    let api = hebi_library(h)?;
    let wait = Duration::from_secs_f64(h.lookup_timeout_s);
    let mut found = hebi::lookup::list(api, &h.interfaces, wait).map_err(anyhow::Error::msg)?;
    found.sort_by(|a, b| (&a.family, &a.name).cmp(&(&b.family, &b.name)));
    let on = if h.interfaces.is_empty() {
        "every interface but loopback".to_owned()
    } else {
        h.interfaces.join(", ")
    };
    let mut out = format!(
        "# libhebi {} ({}): {} module(s) answered on {on} in {:.1} s\n",
        api.version_string(),
        api.path.display(),
        found.len(),
        wait.as_secs_f64()
    );
    out += &format!("{:<12} {:<16} mac\n", "family", "name");
    for f in &found {
        out += &format!("{f}\n");
    }
    Ok(out)
}

/// `[bus] kind = "hebi"`: the group from a lookup (or an imitation group), its gains
/// by role, its lifetime from `network.command_lifetime_s`.
fn hebi_bus(cfg: &Config) -> Result<BuiltBus> {
    let h = &cfg.hebi;
    let api = hebi_library(h)?;
    let spec = hebi_spec(h);
    tracing::info!(?spec, "making the HEBI group");
    let opened = hebi::lookup::open(api, &spec).map_err(anyhow::Error::msg)?;
    let n = opened.names.len();
    let (writer, output) = hebi::mailbox::mailbox(opened.order.clone());
    let counters = writer.counters();
    // SAFETY: a live group of n modules from `open`, handed over.
    let group = unsafe {
        hebi::group::LibGroup::new(
            api,
            opened.group,
            opened.lookup,
            &opened.order,
            opened.imitation,
            writer,
        )
    }
    .map_err(anyhow::Error::msg)?;
    let layout = crate::gait::body::BodyLayout::alternating(
        n,
        cfg.body.first_joint_plane,
        cfg.body.module_length_m,
    );
    let g = &h.gains;
    let settings = if g.all.is_empty() && g.lateral.is_empty() && g.dorsal.is_empty() {
        vec![]
    } else {
        layout
            .planes
            .iter()
            .map(|p| {
                let role = match p {
                    crate::gait::Plane::Lateral => &g.lateral,
                    crate::gait::Plane::Dorsal => &g.dorsal,
                };
                hebi::gains::merge(&g.all, role)
            })
            .collect()
    };
    let start = hebi::Start {
        feedback_rate_hz: cfg.network.feedback_rate_hz as f32,
        command_lifetime_ms: (cfg.network.command_lifetime_s * 1000.0).ceil().max(1.0) as i32,
        settings,
    };
    let bus = hebi::HebiBus::start(Box::new(group), output, counters, &start)
        .map_err(|e| anyhow::anyhow!("starting the HEBI group: {e}"))?;
    Ok(BuiltBus {
        bus: Box::new(bus),
        names: opened.names,
        kind: BusKind::Hebi,
        world: None,
    })
}

/// What a lookup asks for, as an operator reads it.
fn describe(filter: &LookupFilter, expected: Option<usize>) -> String {
    let what = match filter {
        LookupFilter::All => "any module".to_owned(),
        LookupFilter::Family(f) => format!("family {f}"),
        LookupFilter::Names(n) => format!("the modules named {n:?}"),
        LookupFilter::Macs(m) => format!("{} modules by MAC", m.len()),
    };
    match expected {
        Some(n) => format!("{n} of {what}"),
        None => what,
    }
}

fn name(s: &str, key: &str) -> Result<Name> {
    Name::new(s).map_err(|e| anyhow::anyhow!("{key}: {s:?}: {e}"))
}

fn udp_bus(cfg: &Config, stop: &std::sync::atomic::AtomicBool) -> Result<BuiltBus> {
    let net = &cfg.network;
    let mut targets = Vec::new();
    for t in &net.targets {
        targets.extend(udp::parse_targets(t).with_context(|| format!("network.targets: {t:?}"))?);
    }
    let filter = match net.lookup {
        LookupBy::All => LookupFilter::All,
        LookupBy::Family => LookupFilter::Family(name(&net.family, "network.family")?),
        LookupBy::Names => LookupFilter::Names(
            net.names
                .iter()
                .map(|n| name(n, "network.names"))
                .collect::<Result<_>>()?,
        ),
        LookupBy::Macs => LookupFilter::Macs(
            net.macs
                .iter()
                .map(|m| parse_mac(m).with_context(|| format!("network.macs: {m:?}")))
                .collect::<Result<_>>()?,
        ),
    };
    let bind = net.bind.unwrap_or_else(|| udp::default_bind(&targets));
    let timeout = Duration::from_secs_f64(net.discovery_timeout_s);
    let expected = (net.expected_modules > 0).then_some(net.expected_modules);
    tracing::info!(targets = targets.len(), ?filter, "looking up modules");
    let looked_for = format!(
        "module discovery (looking for {} on {})",
        describe(&filter, expected),
        net.targets.join(", ")
    );
    let key = if net.key_file.as_os_str().is_empty() {
        crate::protocol::Key::OPEN
    } else {
        crate::protocol::Key::load(&net.key_file)
            .with_context(|| format!("network.key_file {}", net.key_file.display()))?
    };
    let found = udp::discover_until(&targets, &filter, expected, bind, timeout, &key, stop)
        .context(looked_for)?;
    if found.is_empty() {
        bail!("no modules answered");
    }
    let settings = Settings {
        feedback_rate_hz: net.feedback_rate_hz as f32,
        command_lifetime_s: net.command_lifetime_s as f32,
        strategy: ControlStrategy::Cascaded,
    };
    let session = loop {
        let s: u32 = rand::random();
        if s != crate::protocol::NO_SESSION {
            break s;
        }
    };
    let bus = UdpBus::connect_keyed(&found, settings, bind, session, timeout, key)
        .context("taking the modules")?;
    let names = found.iter().map(|f| f.announce.name.to_string()).collect();
    Ok(BuiltBus {
        bus: Box::new(bus),
        names,
        kind: BusKind::Udp,
        world: None,
    })
}

/// `--emulated`: the same plant as `snake-emu`, stepped in process once per cycle.
fn emulated_bus(cfg: &Config, period_ns: u64) -> Result<BuiltBus> {
    let n = cfg.emulator.modules;
    let emu = &cfg.emulator;
    let mut world = None;
    let plant: Box<dyn Plant> = if emu.world.as_os_str().is_empty() {
        let mut plant_cfg = PlantConfig::new(n);
        plant_cfg.first_plane = cfg.body.first_joint_plane;
        plant_cfg.seed = emu.seed;
        Box::new(JointSpacePlant::new(plant_cfg).context("building the emulated snake")?)
    } else {
        let spec = WorldScenario::load(&emu.world)?.generate_trial(n, emu.world_trial)?;
        let config = PhysicsConfig {
            modules: n,
            first_plane: cfg.body.first_joint_plane,
            seed: emu.seed,
            ..PhysicsConfig::default()
        };
        let plant = PhysicsPlant::new(&spec, config).context("building the emulated world")?;
        world = Some(spec);
        Box::new(plant)
    };
    let bus = SimBus::new(
        plant,
        SimBusConfig {
            period_s: period_ns as f64 * 1e-9,
            command_lifetime_s: cfg.network.command_lifetime_s,
        },
    );
    let family = name(&cfg.network.family, "network.family")?;
    let names = (0..n)
        .map(|i| {
            ModuleIdentity::emulated(i, n, family, EMULATOR_FIRMWARE)
                .name
                .to_string()
        })
        .collect();
    Ok(BuiltBus {
        bus: Box::new(bus),
        names,
        kind: BusKind::Emulated,
        world,
    })
}
