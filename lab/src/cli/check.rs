//! `gvi check SCENE`: symplecticity, energy and momentum-map diagnostics of a run.

use super::run::{SceneArgs, load_scene};
use crate::error::LabError;
use crate::run::{SystemVisitor, visit_system};
use crate::scene::Scene;
use galerkin_vi::geometry::{CheckReport, check_report};
use galerkin_vi::systems::System;

pub fn run_check(args: SceneArgs) -> Result<(), LabError> {
    let scene = load_scene(&args)?;
    struct Check<'a>(&'a Scene);
    impl SystemVisitor for Check<'_> {
        type Output = CheckReport;
        fn visit<S: System + Sync>(self, system: &S) -> Result<CheckReport, LabError> {
            let m = &self.0.method;
            let gvi = m.integrator()?;
            Ok(check_report(
                &gvi,
                system,
                &self.0.initial.q,
                &self.0.initial.p,
                m.steps,
            )?)
        }
    }
    let report = visit_system(&scene.system, Check(&scene))?;
    println!("{report}");
    Ok(())
}
