//! The registry of readings (docs/readings.md, "The readings table"): every step the sources leave
//! open, the spec keys that choose it, the plans' value, and on what that value rests. A reading
//! is *as written* when the text or an equation fixes it, *inferred* when the text is silent and a
//! stated argument chooses, and *calibrated* when it was chosen by its fit to the source's own
//! numbers (the readings score). A calibrated reading names its as-written value: the plan's set
//! [`AS_WRITTEN`] runs its specs under those values, so every claim has an as-written verdict
//! beside the plan's and the readings score prices reading literally.
//!
//! This list is the one place the statuses live: REPORT.md's readings section prints it, and a
//! test holds docs/readings.md's table and the shipped plans' `as_written` sets to it.

use std::fmt::Write;

/// The name of the reading set that puts every calibrated reading at its as-written value.
pub(crate) const AS_WRITTEN: &str = "as_written";

/// How a reading's value was chosen (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Status {
    AsWritten,
    Inferred,
    Calibrated,
}

impl Status {
    pub(crate) fn name(self) -> &'static str {
        match self {
            Status::AsWritten => "as written",
            Status::Inferred => "inferred",
            Status::Calibrated => "calibrated",
        }
    }
}

/// One reading: a row of docs/readings.md's readings table.
#[derive(Debug)]
pub(crate) struct Reading {
    /// The step, word for word the table's first column.
    pub(crate) step: &'static str,
    /// The dotted spec keys that choose it (none: a stated choice in code).
    pub(crate) keys: &'static [&'static str],
    /// The specs of the shipped plans it applies to.
    pub(crate) specs: &'static [&'static str],
    /// The plans' value.
    pub(crate) plan: &'static str,
    pub(crate) status: Status,
    /// For a calibrated reading: each key of its as-written value with that value (TOML), as the
    /// set [`AS_WRITTEN`] sets it.
    pub(crate) as_written: &'static [(&'static str, &'static str)],
    /// The passage it rests on.
    pub(crate) passage: &'static str,
}

const CH5: &[&str] = &["ch5_same", "ch5_diff"];
const CH5_6: &[&str] = &["ch5_same", "ch5_diff", "ch6_same", "ch6_diff", "ch6_exact"];
const CH6: &[&str] = &["ch6_same", "ch6_diff", "ch6_exact"];
const CH6_PSO: &[&str] = &["ch6_same", "ch6_diff"];
const CH4: &[&str] = &["ch4_models"];

/// Every reading, in the order of docs/readings.md's table.
pub(crate) const READINGS: &[Reading] = &[
    Reading {
        step: "Knots when the net is smaller than the grid",
        keys: &["fit.knots", "optimise.knots"],
        specs: CH5_6,
        plan: "eq2_10",
        status: Status::AsWritten,
        as_written: &[],
        passage: "Section 5.2.3: \"the knot vector can be generated with Equations 2.9 - 2.11\"; Eq. 2.10 with n = CN - 1",
    },
    Reading {
        step: "Approach A's surface error",
        keys: &["fit.error_a"],
        specs: CH5,
        plan: "per_surface",
        status: Status::Inferred,
        as_written: &[],
        passage: "Section 5.2.4 gives Eq. 5.13 \"for the improved approach\" only; A follows [23], which fits each surface on its own",
    },
    Reading {
        step: "The exponential method's power factor",
        keys: &["fit.exponential_alpha", "optimise.exponential_alpha"],
        specs: CH5_6,
        plan: "0.8",
        status: Status::AsWritten,
        as_written: &[],
        passage: "Section 2.3.2 and Section 5.3: \"the value of its alpha in Equation 2.8 ... is 0.8\"",
    },
    Reading {
        step: "Which grid lines give the data parameters",
        keys: &["fit.param_rows", "optimise.param_rows"],
        specs: CH5_6,
        plan: "all",
        status: Status::Inferred,
        as_written: &[],
        passage: "Section 5.2.2.1, Eqs. 5.1-5.2: \"the average parameters of each row and column\"; Eq. 5.1 as printed averages one row's own vector (a constant), so the mean over the grid lines is the workable reading",
    },
    Reading {
        step: "Penalised fit (beyond the thesis)",
        keys: &["fit.fairness", "optimise.fairness"],
        specs: CH5_6,
        plan: "0",
        status: Status::AsWritten,
        as_written: &[],
        passage: "Eqs. 5.5-5.6: plain least squares",
    },
    Reading {
        step: "Table 6.1's \"control point coordinate range [-5e-6, 5e-6]\"",
        keys: &["optimise.search_range", "optimise.init_range"],
        specs: CH6,
        plan: "5e-6, 5e-6",
        status: Status::AsWritten,
        as_written: &[],
        passage: "Table 6.1 row 4; Section 6.2.4.2 step 1 (each coordinate plus a value \"within the range of [-5e-6, 5e-6]\"); Section 6.2.2: \"A small range was set as the control point coordinate range because there would be lesser combination of control points\"",
    },
    Reading {
        step: "PSO's velocity clamp",
        keys: &["optimise.pso.vmax_range", "optimise.pso.vmax_fraction"],
        specs: CH6_PSO,
        plan: "search_box, 0.25",
        status: Status::Calibrated,
        as_written: &[("optimise.pso.vmax_fraction", "0.5")],
        passage: "Section 6.2.2 and Table 6.1 row 11: \"half of the range of the data set\"; the plan reads \"the range of the data set\" as the search box for the position bound (row 12), so half of it is 0.5 of the box's width; 0.25 (half of r) reproduces Chapter 6's winners best",
    },
    Reading {
        step: "PSO's position bound",
        keys: &["optimise.pso.position_range"],
        specs: CH6_PSO,
        plan: "search_box",
        status: Status::Inferred,
        as_written: &[],
        passage: "Section 6.2.2: \"maximum position is set to prevent the particle from moving beyond the boundaries of the search space\", the box of Table 6.1 row 4 that holds GA and DE; Table 6.1 row 12 names \"The range of the dataset\"",
    },
    Reading {
        step: "GA's tournament size and mutation range",
        keys: &["optimise.ga.tournament"],
        specs: CH6,
        plan: "4",
        status: Status::AsWritten,
        as_written: &[],
        passage: "Section 6.2.4.1 step 3: \"4 chromosomes are randomly selected\"; Table 6.1's range is the only one Chapter 6 names",
    },
    Reading {
        step: "GA's mutation probability: per gene or per offspring",
        keys: &["optimise.ga.mutation", "optimise.ga.mutated_genes"],
        specs: CH6,
        plan: "per_gene",
        status: Status::Inferred,
        as_written: &[],
        passage: "Section 2.4: \"If the mutation probability is 1, the whole chromosome is altered\" (Pm per gene), against Section 6.2.4.1 step 5: \"A random number is generated and mutation will be executed if the random number is less than\" Pm (one draw per offspring, then \"a predefined number of genes\", Section 2.4, never given)",
    },
    Reading {
        step: "DE's CR and F",
        keys: &["optimise.de.cr", "optimise.de.f"],
        specs: CH6,
        plan: "0.8, 0.3",
        status: Status::Inferred,
        as_written: &[],
        passage: "Table 6.1 rows 7-8 (0.8, 0.3), the chapter's table of settings, against the prose of Section 6.2.2 (0.01, 0.8), whose 0.01 repeats GA's P_m of the sentence before",
    },
    Reading {
        step: "CKSOM at nx != ny",
        keys: &[],
        specs: CH4,
        plan: "six nx x ny faces merged as for a cube",
        status: Status::Inferred,
        as_written: &[],
        passage: "Section 4.3.3, Table 4.13: CKSOM's faces at nx != ny are not described; the holes the cube's merge leaves are the thesis' own finding",
    },
    Reading {
        step: "Oil-tank shape",
        keys: &[],
        specs: CH4,
        plan: "cylinder with spherical-cap domes",
        status: Status::Inferred,
        as_written: &[],
        passage: "Section 3.2.2 and Table 3.1 give the point count and the first ring (y = 0.999462), not the curve",
    },
    Reading {
        step: "The spindle's curve",
        keys: &["som.spindle_profile", "som.spindle_rings"],
        specs: CH4,
        plan: "sin, cos",
        status: Status::Calibrated,
        as_written: &[("som.spindle_profile", "\"sin2\"")],
        passage: "Section 3.2.2 names a \"spindle\" of 7552 points and no curve; Table 3.1's first ring (radius 0.000167 at y = 1.000000) fits no profile. The shape the word names is pointed at both poles (`sin2`); the spheroid `sin` reproduces Appendix B's QE",
    },
    Reading {
        step: "The 3-D SOM's adjacency for TE",
        keys: &["som.som3d_adjacency"],
        specs: CH4,
        plan: "layer",
        status: Status::Calibrated,
        as_written: &[("som.som3d_adjacency", "\"n6\"")],
        passage: "Eq. 4.16: \"not adjacent\", defined nowhere for a lattice; Eqs. 4.4-4.8 measure the lattice distance over I, J and K together, whose distance 1 is the 6-neighbourhood; `layer` reproduces Appendix B's TE",
    },
    Reading {
        step: "QE/TE: online or final map",
        keys: &[],
        specs: &["ch4_models", "ch4_bunny"],
        plan: "online",
        status: Status::AsWritten,
        as_written: &[],
        passage: "Eqs. 4.15-4.16: sums over the T training iterations",
    },
    Reading {
        step: "Seed 003: where CSA/ICSA's nests start",
        keys: &["cuckoo_bezier.start", "cuckoo_bezier.start_spread"],
        specs: &["seed003_cuckoo_bezier"],
        plan: "random",
        status: Status::AsWritten,
        as_written: &[],
        passage: "Section 5.2: \"All data parameters are initialized with random numbers within the hypercube [0,1]^m x [0,1]^n\"",
    },
    Reading {
        step: "Seed 004: what the GA's RMS measures",
        keys: &["closed_cylinder.error"],
        specs: &["seed004_cylinder"],
        plan: "at_parameters",
        status: Status::AsWritten,
        as_written: &[],
        passage: "Eq. 9 fixes the chord-length (u_r, v_s)",
    },
];

/// The readings that apply to any of `specs`.
pub(crate) fn of_specs<'a>(specs: &'a [String]) -> impl Iterator<Item = &'static Reading> + 'a {
    READINGS.iter().filter(move |r| r.specs.iter().any(|s| specs.iter().any(|p| p == s)))
}

/// REPORT.md's table of the readings of a plan's specs with their status (empty without any).
pub(crate) fn markdown(specs: &[String]) -> String {
    let rows: Vec<Vec<String>> = of_specs(specs)
        .map(|r| {
            let keys: Vec<String> = r.keys.iter().map(|k| format!("`{k}`")).collect();
            let written: Vec<String> =
                r.as_written.iter().map(|(k, v)| format!("`{k} = {v}`")).collect();
            vec![
                r.step.replace('|', "\\|"),
                if keys.is_empty() { "code".into() } else { keys.join(", ") },
                format!("`{}`", r.plan),
                format!("**{}**", r.status.name()),
                if written.is_empty() { "-".into() } else { written.join(", ") },
                r.passage.replace('|', "\\|"),
            ]
        })
        .collect();
    if rows.is_empty() {
        return String::new();
    }
    let header: Vec<String> =
        ["step", "spec keys", "the plan's value", "status", "as written", "rests on"]
            .iter()
            .map(|s| s.to_string())
            .collect();
    let calibrated = of_specs(specs).filter(|r| r.status == Status::Calibrated).count();
    let mut s = String::new();
    let calibrated = match calibrated {
        0 => "None of this plan's readings is calibrated, so its verdicts are the as-written ones."
            .to_string(),
        n => format!("{n} of this plan's readings are calibrated; the set `{AS_WRITTEN}` runs their specs at the as-written values."),
    };
    let _ = write!(
        s,
        "\n## The readings and their status\n\nEach step the text leaves open is *as written* (the text or an equation fixes it), *inferred* (the text is silent; a stated argument chooses) or *calibrated* (chosen by its fit to the source's own numbers, the readings score); docs/readings.md gives the arguments and the measurements. {calibrated}\n\n"
    );
    s.push_str(&crate::report::markdown::table(&header, &rows));
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn root() -> &'static Path {
        Path::new(env!("CARGO_MANIFEST_DIR"))
    }

    /// The cells of a Markdown table row (`| a | b \| c |`: an escaped bar stays in its cell).
    fn cells(line: &str) -> Vec<String> {
        let inner = line.trim().trim_start_matches('|').trim_end_matches('|');
        let mut out = vec![String::new()];
        let mut chars = inner.chars().peekable();
        while let Some(c) = chars.next() {
            match c {
                '\\' if chars.peek() == Some(&'|') => {
                    out.last_mut().unwrap().push('|');
                    chars.next();
                }
                '|' => out.push(String::new()),
                c => out.last_mut().unwrap().push(c),
            }
        }
        out.into_iter().map(|c| c.trim().to_string()).collect()
    }

    #[test]
    fn the_docs_readings_table_has_the_registrys_steps_and_statuses() {
        let text = std::fs::read_to_string(root().join("docs/readings.md")).unwrap();
        let table: Vec<&str> = text
            .lines()
            .skip_while(|l| l.trim() != "## The readings table")
            .skip(1)
            .skip_while(|l| !l.starts_with('|'))
            .take_while(|l| l.starts_with('|'))
            .collect();
        assert!(table.len() > 2, "docs/readings.md: no readings table");
        let header = cells(table[0]);
        let step = header.iter().position(|h| h == "step").expect("a step column");
        let status = header.iter().position(|h| h == "status").expect("a status column");
        let rows: Vec<Vec<String>> = table[2..].iter().map(|l| cells(l)).collect();
        assert_eq!(rows.len(), READINGS.len(), "one row per reading of the registry");
        for (row, r) in rows.iter().zip(READINGS) {
            assert_eq!(row[step], r.step, "docs/readings.md's table is in the registry's order");
            let cell = &row[status];
            assert!(
                cell.trim_start_matches('*').starts_with(r.status.name()),
                "{}: the docs say `{cell}`, the registry `{}`",
                r.step,
                r.status.name()
            );
            for (key, value) in r.as_written {
                assert!(
                    cell.contains(value.trim_matches('"')),
                    "{}: the docs' status cell `{cell}` names the as-written {key} = {value}",
                    r.step
                );
            }
        }
    }

    #[test]
    fn every_calibrated_reading_names_its_as_written_value_and_no_other_does() {
        for r in READINGS {
            assert_eq!(r.status == Status::Calibrated, !r.as_written.is_empty(), "{}", r.step);
            for (key, value) in r.as_written {
                assert!(r.keys.contains(key), "{}: {key} is not one of its keys", r.step);
                toml::from_str::<toml::Table>(&format!("v = {value}")).unwrap();
            }
            assert!(!r.specs.is_empty() && !r.passage.is_empty(), "{}", r.step);
        }
    }

    /// A shipped plan running a spec with a calibrated reading has the set `as_written`, which
    /// puts each such reading at its as-written value on exactly the plan's specs it applies to
    /// and sets nothing else.
    #[test]
    fn the_shipped_plans_as_written_sets_follow_the_registry() {
        let dir = root().join("experiments");
        for name in ["thesis", "seeds"] {
            let plan =
                super::super::reproduce::Plan::load(&dir.join(format!("{name}.toml"))).unwrap();
            let calibrated: Vec<&Reading> =
                of_specs(&plan.specs).filter(|r| r.status == Status::Calibrated).collect();
            let set = plan.readings.iter().find(|r| r.name == AS_WRITTEN);
            let Some(set) = set else {
                assert!(calibrated.is_empty(), "{name}: calibrated readings, no `{AS_WRITTEN}`");
                continue;
            };
            let mut keys = Vec::new();
            let mut specs = Vec::new();
            for r in &calibrated {
                for (key, value) in r.as_written {
                    let want: toml::Value = toml::from_str::<toml::Table>(&format!("v = {value}"))
                        .unwrap()["v"]
                        .clone();
                    assert_eq!(set.set.get(*key), Some(&want), "{name}: {AS_WRITTEN}: {key}");
                    keys.push(key.to_string());
                }
                specs.extend(r.specs.iter().filter(|s| plan.specs.iter().any(|p| p == *s)));
            }
            let mut set_keys: Vec<String> = set.set.keys().cloned().collect();
            set_keys.sort();
            keys.sort();
            assert_eq!(set_keys, keys, "{name}: {AS_WRITTEN} sets the calibrated keys only");
            for s in &set.specs {
                assert!(specs.contains(&s.as_str()), "{name}: {AS_WRITTEN} runs {s}");
            }
            for s in specs {
                assert!(set.specs.iter().any(|x| x == s), "{name}: {AS_WRITTEN} misses {s}");
            }
        }
    }

    #[test]
    fn the_report_table_names_each_status_of_a_plans_readings() {
        let md = markdown(&["ch4_models".to_string()]);
        assert!(md.contains("| The 3-D SOM's adjacency for TE | `som.som3d_adjacency` | `layer` | **calibrated** | `som.som3d_adjacency = \"n6\"` |"), "{md}");
        assert!(md.contains("| CKSOM at nx != ny | code |"), "{md}");
        assert!(md.contains("2 of this plan's readings are calibrated"), "{md}");
        assert!(!md.contains("Seed 003"), "{md}");
        let seeds = markdown(&["seed004_cylinder".to_string()]);
        assert!(seeds.contains("None of this plan's readings is calibrated"), "{seeds}");
        assert_eq!(markdown(&["nothing".to_string()]), "");
    }
}
