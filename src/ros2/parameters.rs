//! The node's parameters, served as ROS 2's parameter services (`ros2 param
//! list/get/set/describe`) over the operator's parameters (`operator::parameters`: the
//! same names as Foxglove's Parameters panel): read live from the loop's snapshot; a
//! set goes through the operator API's acts and checks, a refusal coming back as a
//! failed `SetParametersResult` with its reason. There is no parameter store: a change
//! made elsewhere (the socket, Foxglove, the navigator) is what the next `get` reads.
//! `set_parameters_atomically` takes one parameter (several cannot be applied as one).

use std::sync::Arc;

use ros2_client::Node;
use ros2_client::parameters::{ParameterDescriptor, ParameterValue, raw};
use ros2_client::rcl_interfaces::{
    DescribeParametersRequest, DescribeParametersResponse, GetParameterTypesRequest,
    GetParameterTypesResponse, GetParametersRequest, GetParametersResponse, ListParametersRequest,
    ListParametersResponse, ListParametersResult, SetParametersAtomicallyResponse,
    SetParametersRequest, SetParametersResponse,
};
use ros2_client::service::Server;
use serde_json::{Value, json};
use tokio::task::JoinSet;

use super::node::Ros2Error;
use super::operate::{WHO, serve, server};
use crate::operator::parameters::LiveParameters;
use crate::station::services::Operating;

fn value_of(v: &Value) -> ParameterValue {
    match v {
        Value::Bool(b) => ParameterValue::Boolean(*b),
        Value::Number(n) => n
            .as_f64()
            .map_or(ParameterValue::NotSet, ParameterValue::Double),
        Value::String(s) => ParameterValue::String(s.clone()),
        _ => ParameterValue::NotSet,
    }
}

fn json_of(v: &ParameterValue) -> Option<Value> {
    Some(match v {
        ParameterValue::Boolean(b) => json!(b),
        ParameterValue::Integer(i) => json!(*i as f64),
        ParameterValue::Double(x) => json!(x),
        ParameterValue::String(s) => json!(s),
        _ => return None,
    })
}

/// The live parameters by name (`None`: not bound yet).
fn live(op: &Operating) -> Option<(LiveParameters, Vec<(String, Value)>)> {
    let l = LiveParameters::read(op.station.operator().ok()?);
    let all = l.all();
    Some((l, all))
}

fn values(op: &Operating, names: &[String]) -> Vec<ParameterValue> {
    let all = live(op).map(|(_, a)| a).unwrap_or_default();
    names
        .iter()
        .map(|n| {
            all.iter()
                .find(|(k, _)| k == n)
                .map_or(ParameterValue::NotSet, |(_, v)| value_of(v))
        })
        .collect()
}

/// rclcpp's `list_parameters`: with no prefixes, the names with fewer than `depth`
/// dots (0: any); else those equal to a prefix or under `prefix.` within `depth`
/// more levels. `prefixes` are the distinct namespaces of the names listed.
pub fn list(names: &[String], prefixes: &[String], depth: u64) -> ListParametersResult {
    let within = |s: &str| depth == 0 || (s.matches('.').count() as u64) < depth;
    let mut out = ListParametersResult {
        names: vec![],
        prefixes: vec![],
    };
    for name in names {
        let all = prefixes.is_empty() && within(name);
        let under = prefixes.iter().any(|p| {
            name == p
                || name
                    .strip_prefix(p.as_str())
                    .and_then(|r| r.strip_prefix('.'))
                    .is_some_and(|r| within(&format!(".{r}")))
        });
        if all || under {
            out.names.push(name.clone());
            if let Some((ns, _)) = name.rsplit_once('.')
                && !out.prefixes.iter().any(|p| p == ns)
            {
                out.prefixes.push(ns.to_owned());
            }
        }
    }
    out
}

/// Sets one parameter as the operator [`WHO`].
async fn set_one(op: &Operating, p: raw::Parameter) -> raw::SetParametersResult {
    let refused = |reason: String| raw::SetParametersResult {
        successful: false,
        reason,
    };
    let Some((l, _)) = live(op) else {
        return refused("not ready: the control socket is not running yet".into());
    };
    let Some(value) = json_of(&ParameterValue::from(p.value)) else {
        return refused(format!("{}: a number, a boolean or a string", p.name));
    };
    match l.act_for(&p.name, value) {
        Ok(act) => match op.act_logged(WHO, "parameter ", act).await {
            Ok(_) => raw::SetParametersResult {
                successful: true,
                reason: String::new(),
            },
            Err(e) => refused(e.to_string()),
        },
        Err(e) => refused(e),
    }
}

/// The six parameter services.
pub(super) struct ParameterServers {
    get: Server<GetParametersRequest, GetParametersResponse>,
    types: Server<GetParameterTypesRequest, GetParameterTypesResponse>,
    set: Server<SetParametersRequest, SetParametersResponse>,
    atomically: Server<SetParametersRequest, SetParametersAtomicallyResponse>,
    list: Server<ListParametersRequest, ListParametersResponse>,
    describe: Server<DescribeParametersRequest, DescribeParametersResponse>,
}

impl ParameterServers {
    pub fn create(node: &mut Node, private: &str) -> Result<Self, Ros2Error> {
        let t = |ty| ("rcl_interfaces", ty);
        Ok(Self {
            get: server(node, private, "get_parameters", t("GetParameters"))?,
            types: server(node, private, "get_parameter_types", t("GetParameterTypes"))?,
            set: server(node, private, "set_parameters", t("SetParameters"))?,
            atomically: server(
                node,
                private,
                "set_parameters_atomically",
                t("SetParametersAtomically"),
            )?,
            list: server(node, private, "list_parameters", t("ListParameters"))?,
            describe: server(
                node,
                private,
                "describe_parameters",
                t("DescribeParameters"),
            )?,
        })
    }

    /// Serves them in `tasks`.
    pub fn start(self, op: Arc<Operating>, tasks: &mut JoinSet<()>) {
        let o = op.clone();
        tasks.spawn(serve(self.get, move |req: GetParametersRequest| {
            let values = values(&o, &req.names).into_iter().map(Into::into).collect();
            std::future::ready(GetParametersResponse { values })
        }));
        let o = op.clone();
        tasks.spawn(serve(self.types, move |req: GetParameterTypesRequest| {
            let values = values(&o, &req.names)
                .iter()
                .map(ParameterValue::to_parameter_type_raw)
                .collect();
            std::future::ready(GetParameterTypesResponse { values })
        }));
        let o = op.clone();
        tasks.spawn(serve(self.list, move |req: ListParametersRequest| {
            let names: Vec<String> = live(&o)
                .map(|(_, a)| a.into_iter().map(|(n, _)| n).collect())
                .unwrap_or_default();
            let result = list(&names, &req.prefixes, req.depth);
            std::future::ready(ListParametersResponse { result })
        }));
        let o = op.clone();
        tasks.spawn(serve(
            self.describe,
            move |req: DescribeParametersRequest| {
                let values = req
                    .names
                    .iter()
                    .zip(values(&o, &req.names))
                    .map(|(n, v)| match v {
                        ParameterValue::NotSet => ParameterDescriptor::unknown(n).into(),
                        v => ParameterDescriptor::from_value(n, &v).into(),
                    })
                    .collect();
                std::future::ready(DescribeParametersResponse { values })
            },
        ));
        let o = op.clone();
        tasks.spawn(serve(self.set, move |req: SetParametersRequest| {
            let o = o.clone();
            async move {
                let mut results = Vec::new();
                for p in req.parameter {
                    results.push(set_one(&o, p).await);
                }
                SetParametersResponse { results }
            }
        }));
        tasks.spawn(serve(
            self.atomically,
            move |mut req: SetParametersRequest| {
                let o = op.clone();
                async move {
                    let result = match (req.parameter.pop(), req.parameter.is_empty()) {
                        (Some(p), true) => set_one(&o, p).await,
                        (None, _) => raw::SetParametersResult {
                            successful: true,
                            reason: String::new(),
                        },
                        _ => raw::SetParametersResult {
                            successful: false,
                            reason: "several parameters cannot be set as one: set them one \
                                 at a time"
                                .into(),
                        },
                    };
                    SetParametersAtomicallyResponse { result }
                }
            },
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn listing_follows_rclcpp() {
        let names: Vec<String> = [
            "gait",
            "params.a",
            "controller.config.x.y",
            "controller.name",
        ]
        .map(String::from)
        .into();
        let all = list(&names, &[], 0);
        assert_eq!(all.names, names);
        assert_eq!(
            all.prefixes,
            ["params", "controller.config.x", "controller"]
        );
        assert_eq!(list(&names, &[], 1).names, ["gait"]);
        assert_eq!(
            list(&names, &["controller".into()], 2).names,
            ["controller.name"]
        );
        assert_eq!(
            list(&names, &["controller".into()], 0).names,
            ["controller.config.x.y", "controller.name"]
        );
    }

    #[test]
    fn values_cross_as_ros_2_types() {
        assert_eq!(value_of(&json!(1.5)), ParameterValue::Double(1.5));
        assert_eq!(value_of(&json!(true)), ParameterValue::Boolean(true));
        assert_eq!(value_of(&json!("x")), ParameterValue::String("x".into()));
        assert_eq!(json_of(&ParameterValue::Integer(2)), Some(json!(2.0)));
        assert_eq!(json_of(&ParameterValue::ByteArray(vec![1])), None);
    }
}
