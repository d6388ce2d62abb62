//! `sweep predict`: a sweep's answer (MFR, or its layout's own quantity) at a setting from its
//! emulator.

use std::path::PathBuf;

use super::error::CliError;
use clap::Args;
use demsweep::error::Error;

#[derive(Args)]
pub(super) struct PredictArgs {
    /// A sweep directory (holding manifest.json) with done points.
    dir: PathBuf,
    /// Parameter values, e.g. --set diameter=2,gap=4 (units of the sweep file); unset
    /// parameters take the middle of their range. Values outside the swept range are predicted
    /// with a warning: the emulator extrapolates there.
    #[arg(long, value_delimiter = ',')]
    set: Vec<String>,
    /// Print the prediction as JSON.
    #[arg(long)]
    json: bool,
}

pub(super) fn predict(a: PredictArgs) -> Result<(), Error> {
    // A calibration's runs are pours (no MFR): it read "needs at least 8 done points" with 120.
    if demsweep::run::calibrate::settings(&a.dir).is_some() {
        let dir = demsweep::sys::shell::quote_path(&a.dir).into_owned();
        return Err(super::error::flag(
            a.dir.display().to_string(),
            format!(
                "a calibration directory: predict reads a spreading sweep's MFR; a calibration's answer is its \
                 posterior (posterior.json, `sweep report {dir}`)"
            ),
        ));
    }
    let p = demsweep::report::emulation::predict(&a.dir, &a.set)?;
    for name in &p.outside {
        eprintln!(
            "warning: {name} = {} lies outside the sampled range: the emulator extrapolates",
            p.parameters[name]
        );
    }
    if a.json {
        println!("{}", serde_json::to_string_pretty(&p).map_err(CliError::Json)?);
    } else {
        let setting: Vec<String> = p.parameters.iter().map(|(k, v)| format!("{k}={v}")).collect();
        let name = p.answer.kind.words();
        println!("{name} {:.4} ± {:.4} (predictive SE) at {}", p.answer.value, p.se, setting.join(", "));
        println!("emulator: {} points, leave-one-out RMSE {:.4}", p.points, p.loo_rmse);
    }
    Ok(())
}
