//! The report on a campaign with the predictor axis (`bkpbs campaign --predictors`): each
//! planner under each predictor is one arm of the comparison, named `planner+predictor`
//! (`bk-pbs+constant`), so the tables show them side by side and `--versus bk-pbs+learned`
//! pairs the predictors cell by cell and seed by seed, as it pairs planners.

use crate::campaign::results::Results;
use crate::campaign::table::Table;

/// `results` with every row's planner replaced by its arm and the predictor column dropped;
/// results without the predictor axis as they are.
pub fn by_arm(mut results: Results) -> Results {
    if !results.axes.predictor {
        return results;
    }
    for table in [
        &mut results.episodes,
        &mut results.vehicles,
        &mut results.timings,
        &mut results.failures,
        &mut results.regions,
        &mut results.entries,
    ] {
        to_arms(table);
    }
    results.planners = results
        .planners
        .iter()
        .flat_map(|p| results.predictors.iter().map(move |q| format!("{p}+{q}")))
        .filter(|arm| {
            let rows = [&results.episodes, &results.failures];
            rows.iter()
                .any(|t| t.rows.iter().any(|r| &r.cell.planner == arm))
        })
        .collect();
    results.predictors.clear();
    results.axes.predictor = false;
    results
}

/// The table's rows named by their arm, without the predictor column (a table without one,
/// an empty `regions.csv` on the paper's demand, as it is).
fn to_arms(table: &mut Table) {
    let (Some(planner), Some(predictor)) = (table.column("planner"), table.column("predictor"))
    else {
        return;
    };
    table.header.remove(predictor);
    for row in &mut table.rows {
        let arm = row.cell.arm();
        let mut fields = csv::StringRecord::new();
        for (i, f) in row.fields.iter().enumerate() {
            match i {
                _ if i == planner => fields.push_field(&arm),
                _ if i == predictor => {}
                _ => fields.push_field(f),
            }
        }
        row.fields = fields;
        row.cell.planner = arm;
        row.cell.predictor = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::grid::Cell;
    use crate::campaign::table::{Axes, Row, CELL_COLUMNS};

    fn row(planner: &str, predictor: &str, seed: u64) -> Row {
        let cell = Cell {
            planner: planner.into(),
            alpha: 0.5,
            lambda: 3000.0,
            seed,
            hdv_profile: "sumo-safe".into(),
            predictor: Some(predictor.into()),
            scenario: None,
        };
        let axes = Axes {
            predictor: true,
            ..Axes::default()
        };
        let fields = axes.row(
            &cell,
            &CELL_COLUMNS,
            [
                planner,
                "0.5",
                "3000",
                &seed.to_string(),
                "sumo-safe",
                "1.5",
            ],
        );
        Row { cell, fields }
    }

    #[test]
    fn each_planner_under_each_predictor_is_an_arm() {
        let axes = Axes {
            predictor: true,
            ..Axes::default()
        };
        let mut results = Results::empty(axes);
        results.episodes.header = axes.header(&[
            "planner",
            "alpha",
            "lambda",
            "seed",
            "hdv_profile",
            "mean_delay_s",
        ]);
        results.planners = vec!["bk-pbs".into(), "idm-mobil".into()];
        results.predictors = vec!["learned".into(), "constant".into()];
        results.episodes.rows = vec![
            row("bk-pbs", "learned", 1),
            row("bk-pbs", "constant", 1),
            row("idm-mobil", "learned", 1),
        ];
        let arms = by_arm(results);
        assert_eq!(
            arms.planners,
            ["bk-pbs+learned", "bk-pbs+constant", "idm-mobil+learned"]
        );
        assert_eq!(arms.episodes.header[..2], ["planner", "alpha"]);
        let first = &arms.episodes.rows[1];
        assert_eq!(first.cell.planner, "bk-pbs+constant");
        assert_eq!(
            first.fields.iter().collect::<Vec<_>>(),
            ["bk-pbs+constant", "0.5", "3000", "1", "sumo-safe", "1.5"]
        );
        assert_eq!(arms.axes, Axes::default());
    }
}
