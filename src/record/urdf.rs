//! The robot's model as a URDF, from the body layout the recording draws: the head link
//! `body` (the `body` frame: x toward the nose, z up), then one link per joint, each a
//! cylinder one module long with the modules' radius, joined by revolute joints named
//! after the modules, about z (lateral) or −y (dorsal), one module apart along −x — the
//! conventions of `record::kinematics` and the physics plant. A link's frame is its
//! joint's (URDF's rule), so `module_k` sits at the joint, its cylinder half a module
//! behind it. Served by the live view
//! as the asset [`URDF_URI`]; `snaked --urdf` prints it for other tools.

use std::fmt::Write;

use crate::gait::{BodyLayout, JOINT_LIMIT_RAD, Plane};
use crate::module::{MODULE_MAX_SPEED_RAD_S, MODULE_MAX_TORQUE_NM, MODULE_RADIUS_M};

/// The asset's URI (Foxglove's 3-D panel: a URDF layer with this URL).
pub const URDF_URI: &str = "package://snaked/urdf/snake.urdf";
/// The modules' peak torque and the motor's speed (SPEC §1), for the limits.
const EFFORT_NM: f64 = MODULE_MAX_TORQUE_NM;
const VELOCITY_RAD_S: f64 = MODULE_MAX_SPEED_RAD_S;

/// The URDF of `layout`; joint `k` is named `names[k]` (or `joint_k`).
pub fn urdf(layout: &BodyLayout, names: &[String]) -> String {
    let l = layout.module_length_m;
    let r = MODULE_RADIUS_M;
    let mut s = String::from("<?xml version=\"1.0\"?>\n<robot name=\"snake\">\n");
    let link = |s: &mut String, name: &str, x: f64| {
        // A cylinder's axis is its z: turned onto x.
        let _ = writeln!(
            s,
            "  <link name=\"{name}\">\n    <visual>\n      <origin xyz=\"{x} 0 0\" rpy=\"0 1.5707963267948966 0\"/>\n      \
             <geometry><cylinder radius=\"{r}\" length=\"{l}\"/></geometry>\n      \
             <material name=\"module\"><color rgba=\"0.85 0.45 0.1 1\"/></material>\n    </visual>\n  </link>"
        );
    };
    link(&mut s, "body", 0.0);
    let mut parent = "body".to_owned();
    for (k, plane) in layout.planes.iter().enumerate() {
        let child = format!("module_{}", k + 1);
        link(&mut s, &child, -0.5 * l);
        let name = names
            .get(k)
            .cloned()
            .unwrap_or_else(|| format!("joint_{k}"));
        let axis = match plane {
            Plane::Lateral => "0 0 1",
            Plane::Dorsal => "0 -1 0",
        };
        // Joint 0 half a module behind the head link's centre, the others a module apart.
        let _ = writeln!(
            s,
            "  <joint name=\"{name}\" type=\"revolute\">\n    <parent link=\"{parent}\"/>\n    \
             <child link=\"{child}\"/>\n    <origin xyz=\"{} 0 0\" rpy=\"0 0 0\"/>\n    <axis xyz=\"{axis}\"/>\n    \
             <limit lower=\"{}\" upper=\"{JOINT_LIMIT_RAD}\" effort=\"{EFFORT_NM}\" velocity=\"{VELOCITY_RAD_S}\"/>\n  </joint>",
            if k == 0 { -0.5 * l } else { -l },
            -JOINT_LIMIT_RAD,
        );
        parent = child;
    }
    s.push_str("</robot>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_link_per_joint_and_the_joints_planes() {
        let layout = BodyLayout::alternating(4, Plane::Lateral, 0.064);
        let names: Vec<String> = (1..=4).map(|k| format!("module-{k:02}")).collect();
        let u = urdf(&layout, &names);
        assert_eq!(u.matches("<link ").count(), 5);
        assert_eq!(u.matches("type=\"revolute\"").count(), 4);
        assert_eq!(u.matches("<axis xyz=\"0 0 1\"/>").count(), 2);
        assert_eq!(u.matches("<axis xyz=\"0 -1 0\"/>").count(), 2);
        assert!(u.contains("<joint name=\"module-01\""));
        assert!(
            u.contains("<origin xyz=\"-0.032 0 0\" rpy=\"0 0 0\"/>"),
            "joint 0"
        );
        assert_eq!(
            u.matches("<origin xyz=\"-0.064 0 0\" rpy=\"0 0 0\"/>")
                .count(),
            3
        );
        assert!(u.starts_with("<?xml") && u.trim_end().ends_with("</robot>"));
    }
}
