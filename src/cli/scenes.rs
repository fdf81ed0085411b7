//! `springlab scenes`: the built-in catalogue, each scene's own parameters, and the method
//! parameters of the method asked for.
//!
//! ```text
//! springlab scenes                         every scene with its own parameters; which method
//!                                          parameters exist and for which method
//! springlab scenes rope                    one scene: its parameters, default method, dt and
//!                                          duration, and its method parameters' defaults by method
//! springlab scenes rope --method verlet    the same with Verlet's parameters in full
//! springlab scenes --method xpbd           every scene with XPBD's parameters
//! ```

use std::io::Write;

use anyhow::bail;
use clap::Args;

use crate::physics::Method;
use crate::scene::{self, BUILTIN, ParamSpec, SceneDef, method_param};

/// Options of `springlab scenes`.
#[derive(Debug, Args)]
pub struct ScenesArgs {
    /// One built-in scene (default: all of them).
    pub scene: Option<String>,
    /// Also list the parameters of this method (for example `verlet`), with each scene's
    /// defaults.
    #[arg(long, short)]
    pub method: Option<String>,
}

fn line(out: &mut impl Write, p: &ParamSpec) -> std::io::Result<()> {
    let value = if p.unit.is_empty() {
        p.default.to_string()
    } else {
        format!("{} {}", p.default, p.unit)
    };
    writeln!(
        out,
        "    {:<20} = {value:<16} {} ({})",
        p.name,
        p.doc,
        p.expected()
    )
}

/// The scene's own parameters (not the methods').
fn own(def: &SceneDef) -> Vec<ParamSpec> {
    (def.params)()
        .into_iter()
        .filter(|p| method_param(p.name).is_none())
        .collect()
}

/// The scene's parameters of `method`.
fn of_method(def: &SceneDef, method: Method) -> Vec<ParamSpec> {
    (def.params)()
        .into_iter()
        .filter(|p| method_param(p.name).is_some_and(|m| m.contains(&method)))
        .collect()
}

/// The methods that have parameters, in teaching order.
fn methods_with_parameters() -> Vec<Method> {
    Method::ALL
        .into_iter()
        .filter(|m| !m.declaration().params.is_empty())
        .collect()
}

fn method_section(out: &mut impl Write, def: &SceneDef, method: Method) -> std::io::Result<()> {
    let params = of_method(def, method);
    if params.is_empty() {
        writeln!(out, "  {method}: no parameters")?;
    } else {
        writeln!(
            out,
            "  {method} parameters (they change only a run with {method}):"
        )?;
        for p in &params {
            line(out, p)?;
        }
    }
    Ok(())
}

/// `springlab scenes [SCENE] [--method M]`.
///
/// # Errors
/// An unknown scene or method; standard output cannot be written.
pub fn list(args: &ScenesArgs) -> anyhow::Result<()> {
    let method = match &args.method {
        Some(text) => Some(text.trim().parse::<Method>()?),
        None => None,
    };
    let defs: Vec<&SceneDef> = match &args.scene {
        Some(name) => match scene::builtin(name) {
            Some(def) => vec![def],
            None => bail!(
                "unknown scene `{name}`; built-in scenes: {}",
                BUILTIN
                    .iter()
                    .map(|d| d.name)
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        },
        None => BUILTIN.iter().collect(),
    };
    let mut out = std::io::stdout().lock();
    for def in &defs {
        writeln!(out, "{:<14} {}", def.name, def.summary)?;
        if args.scene.is_some() {
            // One scene: what it starts with.
            let built = (def.build)(&def.default_params())?;
            writeln!(
                out,
                "  default method {}, dt = {} s, duration {} s",
                built.method_label(),
                crate::budget::short(built.dt),
                crate::budget::short(built.duration)
            )?;
            writeln!(out, "  scene parameters:")?;
        }
        for p in own(def) {
            line(&mut out, &p)?;
        }
        if let Some(m) = method {
            method_section(&mut out, def, m)?;
        } else if args.scene.is_some() {
            let summary: Vec<String> = methods_with_parameters()
                .into_iter()
                .map(|m| {
                    let values: Vec<String> = of_method(def, m)
                        .iter()
                        .map(|p| format!("{} = {}", p.name, p.default))
                        .collect();
                    format!("{m}: {}", values.join(", "))
                })
                .collect();
            writeln!(
                out,
                "  method parameters (--method M lists one method's in full): {}",
                summary.join("; ")
            )?;
        }
    }
    if args.scene.is_none() && method.is_none() {
        writeln!(
            out,
            "\nMethod parameters: set like the scene's (--set), each changes only a run with its \
             method; defaults per scene with `springlab scenes SCENE --method M`:"
        )?;
        for m in methods_with_parameters() {
            let names = m.declaration().params.join(", ");
            writeln!(out, "  {:<20} {names}", m.name())?;
        }
        let none: Vec<&str> = Method::ALL
            .into_iter()
            .filter(|m| !methods_with_parameters().contains(m))
            .map(Method::name)
            .collect();
        writeln!(out, "  no parameters: {}", none.join(", "))?;
    }
    Ok(())
}
