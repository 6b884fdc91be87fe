//! The registry's machinery: what a controller kind declares ([`ControllerKind`]),
//! its type-erased face ([`Family`]), and choosing and building a controller by name
//! ([`Selection`], [`build`]). The list itself is `crate::controllers::REGISTRY`, one
//! line per controller. Everything here runs off the loop (building allocates).

use std::marker::PhantomData;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::catalog::{self, ControllerInfo};
use super::config::{self, ConfigError};
use super::interface::Controller;
use super::report::ReportSpec;
use crate::gait::{BodyLayout, GaitKind, GaitParams};

/// What a controller is built for.
#[derive(Debug, Clone, Copy)]
pub struct BuildContext<'a> {
    pub gait: GaitKind,
    pub layout: &'a BodyLayout,
    /// The gait's nominal parameters now (the controller must accept them).
    pub params: &'a GaitParams,
}

/// A controller kind: its typed configuration, presets, checks and builder.
pub trait ControllerKind: 'static {
    /// Serde with `deny_unknown_fields`, so a misspelt override is an error.
    type Config: Serialize + DeserializeOwned + Clone + Send + 'static;
    /// Its name on the socket, in `snakectl`, the config file and the lab.
    const NAME: &'static str;
    const SUMMARY: &'static str;
    /// The gaits it can run.
    const GAITS: &'static [GaitKind];
    /// Preset names and what each is; the first is the default.
    const PRESETS: &'static [(&'static str, &'static str)];
    fn preset(name: &str) -> Option<Self::Config>;
    /// Every bound of the configuration (field paths relative to the configuration).
    fn check(config: &Self::Config, ctx: &BuildContext<'_>) -> Result<(), ConfigError>;
    /// Names and units of its report (must fit `ControllerReport`).
    fn report_spec(config: &Self::Config, ctx: &BuildContext<'_>) -> ReportSpec;
    fn build(config: &Self::Config, ctx: &BuildContext<'_>) -> Box<dyn Controller>;
}

/// A registered controller kind, type-erased.
pub trait Family: Sync {
    fn name(&self) -> &'static str;
    fn summary(&self) -> &'static str;
    fn gaits(&self) -> &'static [GaitKind];
    fn presets(&self) -> &'static [(&'static str, &'static str)];
    /// A preset's whole configuration as JSON.
    fn preset_config(&self, preset: &str) -> Option<Value>;
    /// The report's names and units for a preset (as `controller.list` shows them).
    fn preset_report(&self, preset: &str, ctx: &BuildContext<'_>) -> Option<ReportSpec>;
    /// Builds `preset` with `overrides` merged onto it.
    fn build(
        &self,
        preset: &'static str,
        overrides: Option<&Value>,
        ctx: &BuildContext<'_>,
    ) -> Result<Built, ConfigError>;
}

/// The registry's entry for `K`.
pub struct Entry<K>(PhantomData<fn() -> K>);

impl<K> Entry<K> {
    pub const NEW: Entry<K> = Entry(PhantomData);
}

impl<K: ControllerKind> Family for Entry<K> {
    fn name(&self) -> &'static str {
        K::NAME
    }
    fn summary(&self) -> &'static str {
        K::SUMMARY
    }
    fn gaits(&self) -> &'static [GaitKind] {
        K::GAITS
    }
    fn presets(&self) -> &'static [(&'static str, &'static str)] {
        K::PRESETS
    }
    fn preset_config(&self, preset: &str) -> Option<Value> {
        K::preset(preset).map(|c| config::to_json(&c))
    }
    fn preset_report(&self, preset: &str, ctx: &BuildContext<'_>) -> Option<ReportSpec> {
        K::preset(preset).map(|c| K::report_spec(&c, ctx))
    }
    fn build(
        &self,
        preset: &'static str,
        overrides: Option<&Value>,
        ctx: &BuildContext<'_>,
    ) -> Result<Built, ConfigError> {
        let base = K::preset(preset).ok_or_else(|| unknown_preset(self, preset))?;
        let config: K::Config =
            config::with_overrides(&base, overrides).map_err(|e| e.under("config"))?;
        K::check(&config, ctx).map_err(|e| e.under("config"))?;
        let report = K::report_spec(&config, ctx);
        debug_assert!(report.fits(), "{} reports more than fits", K::NAME);
        let controller = K::build(&config, ctx);
        controller.accepts(ctx.params)?;
        Ok(Built {
            controller,
            info: ControllerInfo {
                id: catalog::next_id(),
                gait: ctx.gait,
                controller: K::NAME,
                preset,
                config: config::to_json(&config),
                report,
            },
        })
    }
}

/// A built controller and what it is (its id is fresh).
pub struct Built {
    pub controller: Box<dyn Controller>,
    pub info: ControllerInfo,
}

/// Which controller to run, as the socket, the config file and the lab name it:
/// `controller` is a controller's name (its default preset) or, for short, a preset's
/// name that only one controller of the gait has; `config` overrides the preset.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Selection {
    pub controller: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub preset: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub config: Option<Value>,
}

impl Selection {
    pub fn named(name: &str) -> Self {
        Self {
            controller: name.to_owned(),
            ..Self::default()
        }
    }
}

/// The registry's controllers that run `gait`.
pub fn for_gait(
    registry: &'static [&'static dyn Family],
    gait: GaitKind,
) -> impl Iterator<Item = &'static dyn Family> {
    registry
        .iter()
        .copied()
        .filter(move |f| f.gaits().contains(&gait))
}

/// The family and preset a selection names for `gait`.
pub fn resolve(
    registry: &'static [&'static dyn Family],
    gait: GaitKind,
    sel: &Selection,
) -> Result<(&'static dyn Family, &'static str), ConfigError> {
    let name = sel.controller.as_str();
    if let Some(f) = registry.iter().copied().find(|f| f.name() == name) {
        if !f.gaits().contains(&gait) {
            return Err(ConfigError::WrongGait {
                controller: f.name(),
                gait: gait.name(),
                gaits: join(f.gaits().iter().map(|g| g.name())),
            });
        }
        let preset = match &sel.preset {
            None => f.presets()[0].0,
            Some(p) => find_preset(f, p)?,
        };
        return Ok((f, preset));
    }
    // A preset's name, if exactly one controller of the gait has it.
    let mut hits = for_gait(registry, gait).filter_map(|f| {
        f.presets()
            .iter()
            .find(|(p, _)| *p == name)
            .map(|(p, _)| (f, *p))
    });
    match (hits.next(), hits.next(), &sel.preset) {
        (Some(hit), None, None) => Ok(hit),
        (Some((f, _)), None, Some(_)) => Err(ConfigError::invalid(
            "preset",
            format!(
                "`{name}` is already a preset of {}: give the controller's name",
                f.name()
            ),
        )),
        _ => Err(ConfigError::UnknownController {
            gait: gait.name(),
            name: name.to_owned(),
            known: known_names(registry, gait),
        }),
    }
}

/// Builds what `sel` names for `ctx.gait` (allocates: never in the loop thread).
pub fn build(
    registry: &'static [&'static dyn Family],
    sel: &Selection,
    ctx: &BuildContext<'_>,
) -> Result<Built, ConfigError> {
    let (family, preset) = resolve(registry, ctx.gait, sel)?;
    family.build(preset, sel.config.as_ref(), ctx)
}

/// Every name a selection for `gait` may use: controllers, then their presets.
pub fn known_names(registry: &'static [&'static dyn Family], gait: GaitKind) -> String {
    let families = for_gait(registry, gait).map(|f| f.name());
    let presets = for_gait(registry, gait).flat_map(|f| f.presets().iter().map(|p| p.0));
    let mut all: Vec<&str> = families.chain(presets).collect();
    all.dedup();
    all.join(", ")
}

fn find_preset(f: &dyn Family, name: &str) -> Result<&'static str, ConfigError> {
    f.presets()
        .iter()
        .find(|(p, _)| *p == name)
        .map(|(p, _)| *p)
        .ok_or_else(|| unknown_preset(f, name))
}

fn unknown_preset(f: &dyn Family, name: &str) -> ConfigError {
    ConfigError::UnknownPreset {
        controller: f.name(),
        name: name.to_owned(),
        known: join(f.presets().iter().map(|p| p.0)),
    }
}

fn join<'a>(names: impl Iterator<Item = &'a str>) -> String {
    names.collect::<Vec<_>>().join(", ")
}
