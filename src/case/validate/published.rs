//! `[[reference.values]]` and `[reference.short]`: published values, each with its quantity
//! parsed into the vocabulary of `case::published`, its number, exactly one tolerance and its
//! source; and the settings of the shorter variant that `cargo test` runs.
use super::super::published::{Published, PublishedValue, Quantity, Tolerance};
use super::super::raw::{RawPublished, RawReference};
use super::super::Analysis;
use super::{CaseError, Validator};
use crate::model::mesh::Mesh;

impl Validator<'_> {
    /// The published values of `[reference]` and its `short` variant. A quantity that this
    /// case cannot compute (a node beyond the rod, any value of a clip, which has no single
    /// final state) is refused here; a `metric.KEY` that the run does not write is refused
    /// before the run (`engine::published::unavailable`).
    pub(super) fn published(
        &self,
        r: Option<&RawReference>,
        mesh: &Mesh,
        analysis: &Analysis,
    ) -> Result<Published, CaseError> {
        let Some(r) = r else { return Ok(Published::default()) };
        let is_clip = matches!(analysis, Analysis::Inverse(s) if matches!(s.data, super::super::DataSource::Clip(_)));
        if is_clip && !r.values.is_empty() {
            return Err(self.err(
                "reference.values",
                "a clip case is solved frame by frame and has no single final state to check a published value on",
            ));
        }
        let mut values: Vec<PublishedValue> = Vec::with_capacity(r.values.len());
        for (i, raw) in r.values.iter().enumerate() {
            let v = self.published_value(&format!("reference.values[{i}]"), raw, mesh)?;
            if let Some(j) = values.iter().position(|w| w.quantity == v.quantity) {
                return Err(self.err(
                    &format!("reference.values[{i}].quantity"),
                    format!(
                        "`{}` is given twice (also reference.values[{j}]): give one published value per quantity",
                        v.quantity
                    ),
                ));
            }
            values.push(v);
        }
        if values.is_empty() && !r.short.is_empty() {
            return Err(self.err("reference.short", "a shorter variant for the test needs published values to check"));
        }
        Ok(Published { values, short: r.short.iter().map(|(k, v)| (k.clone(), v.clone())).collect() })
    }

    /// One `[[reference.values]]` row (`key`: `reference.values[i]`).
    fn published_value(&self, key: &str, raw: &RawPublished, mesh: &Mesh) -> Result<PublishedValue, CaseError> {
        let quantity =
            Quantity::parse(&raw.quantity).map_err(|e| self.err(&format!("{key}.quantity"), e.to_string()))?;
        if let Quantity::Node { s_m, .. } = quantity {
            if !(0.0..=mesh.length_m).contains(&s_m) {
                return Err(self.err(
                    &format!("{key}.quantity"),
                    format!(
                        "`{}`: the arc length {s_m} m lies outside the rod, [0, {}] m",
                        raw.quantity.trim(),
                        mesh.length_m
                    ),
                ));
            }
        }
        let value = self.scalar(&format!("{key}.value"), &raw.value)?;
        let tolerance = match (&raw.tolerance_abs, &raw.tolerance_rel) {
            (Some(t), None) => Tolerance::Absolute(self.positive(&format!("{key}.tolerance_abs"), t)?),
            (None, Some(t)) => Tolerance::Relative(self.positive(&format!("{key}.tolerance_rel"), t)?),
            (Some(_), Some(_)) => return Err(self.err(
                &format!("{key}.tolerance_rel"),
                "give exactly one of tolerance_abs (in the quantity's unit) and tolerance_rel (of |value|), not both",
            )),
            (None, None) => {
                return Err(self.err(
                    &format!("{key}.tolerance_abs"),
                    format!(
                        "a published value needs a tolerance: tolerance_abs [{}] or tolerance_rel (of |value|)",
                        quantity.unit()
                    ),
                ))
            }
        };
        if let (Tolerance::Relative(_), 0.0) = (tolerance, value) {
            return Err(self.err(
                &format!("{key}.tolerance_rel"),
                "a relative tolerance of a published 0 allows no difference at all: give tolerance_abs",
            ));
        }
        let source = raw.source.as_deref().map(str::trim).filter(|s| !s.is_empty()).ok_or_else(|| {
            self.err(
                &format!("{key}.source"),
                "every published value needs its source: authors, year, journal, and the table, figure or equation",
            )
        })?;
        let note = raw.note.as_deref().map(str::trim).filter(|s| !s.is_empty()).map(String::from);
        Ok(PublishedValue { quantity, value, tolerance, source: source.to_string(), note })
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use crate::case::published::Setting;
    use crate::case::published::{Axis, NodeField, Quantity, Tolerance};
    use crate::case::{Case, CaseError, Reference};

    const CASE: &str = r#"
description = "test"
[constants]
L = 2.0
P = 1e-3
[rod]
length_m = "L"
elements = 10
[material]
young_modulus_pa = 1e7
shear_modulus_pa = 4e6
shear_correction = 1
[cross_section]
shape = "circle"
radius_m = 0.01
[loads]
end_force_n = [0, "-P", 0]
[solver]
analysis = "static"
method = "newton"
tolerance = 1e-10
max_iterations = 20
"#;

    const ROW: &str = r#"
[[reference.values]]
quantity = "tip.y_m"
value = "-0.5*L"
tolerance_abs = 1e-3
source = "A. Author (1999), J. Mech. 1, Table 2"
"#;

    fn parse(text: &str) -> Result<Case, CaseError> {
        Case::from_toml(text, "t", Path::new("t.toml"))
    }

    /// The error's key and reason (which must hold every word).
    fn refused(text: &str, key: &str, words: &[&str]) {
        match parse(text) {
            Err(CaseError::Invalid { key: k, reason, .. }) => {
                assert_eq!(k, key, "{reason}");
                for w in words {
                    assert!(reason.contains(w), "`{reason}` lacks `{w}`");
                }
            }
            other => panic!("expected an error at {key}, got {other:?}"),
        }
    }

    #[test]
    fn rows_are_typed_with_their_tolerance_and_source() {
        let text = format!(
            "{CASE}{ROW}\n[[reference.values]]\nquantity = \"node(s=0.5).displacement_x_m\"\nvalue = 0\ntolerance_abs = 1e-6\nsource = \"B\"\nnote = \" half-way \"\n\n[[reference.values]]\nquantity = \"metric.iterations\"\nvalue = 12\ntolerance_rel = 0.25\nsource = \"C\"\n"
        );
        let c = parse(&text).unwrap();
        let v = &c.checks.published.values;
        assert_eq!(v.len(), 3);
        assert_eq!(v[0].quantity, Quantity::Tip(NodeField::Position(Axis::Y)));
        assert_eq!((v[0].value, v[0].tolerance), (-1.0, Tolerance::Absolute(1e-3)));
        assert_eq!(v[0].source, "A. Author (1999), J. Mech. 1, Table 2");
        assert_eq!(v[1].quantity, Quantity::Node { s_m: 0.5, field: NodeField::Displacement(Axis::X) });
        assert_eq!(v[1].note.as_deref(), Some("half-way"));
        assert_eq!(
            (v[2].quantity.clone(), v[2].tolerance),
            (Quantity::Metric("iterations".into()), Tolerance::Relative(0.25))
        );
        assert_eq!(c.checks.reference, None);
        assert!(c.short_variant().unwrap().is_none());
    }

    /// The analytic theory keeps its form, alone or beside published values.
    #[test]
    fn the_theory_of_reference_kind_is_unchanged() {
        let kind = "\n[reference]\nkind = \"tip_loaded_cantilever\"\nforce_n = \"P\"\n";
        let c = parse(&format!("{CASE}{kind}")).unwrap();
        assert_eq!(c.checks.reference, Some(Reference::TipLoadedCantilever { force_n: 1e-3 }));
        assert!(c.checks.published.values.is_empty());
        let both = parse(&format!("{CASE}{kind}{ROW}")).unwrap();
        assert_eq!((both.checks.reference.is_some(), both.checks.published.values.len()), (true, 1));
        refused(&format!("{CASE}\n[reference]\nforce_n = \"P\"\n"), "reference.force_n", &["only with kind"]);
        refused(
            &format!("{CASE}\n[reference]\nkind = \"tip_loaded_cantilever\"\n"),
            "reference.force_n",
            &["required"],
        );
    }

    /// Each mistake names its key and what is allowed.
    #[test]
    fn mistakes_name_the_key() {
        let with = |from: &str, to: &str| format!("{CASE}{}", ROW.replace(from, to));
        refused(
            &with("tip.y_m", "tip.deflection_m"),
            "reference.values[0].quantity",
            &["unknown field `deflection_m`", "tip.displacement_x_m", "node(s=S).FIELD", "metric.KEY"],
        );
        refused(&with("tip.y_m", "tipp.y_m"), "reference.values[0].quantity", &["not a quantity", "tip.x_m"]);
        refused(&with("tip.y_m", "node(s=2.5).x_m"), "reference.values[0].quantity", &["outside the rod", "[0, 2] m"]);
        refused(
            &with("source = \"A. Author (1999), J. Mech. 1, Table 2\"", ""),
            "reference.values[0].source",
            &["source"],
        );
        refused(
            &with("source = \"A. Author (1999), J. Mech. 1, Table 2\"", "source = \" \""),
            "reference.values[0].source",
            &["source"],
        );
        refused(
            &with("tolerance_abs = 1e-3", ""),
            "reference.values[0].tolerance_abs",
            &["tolerance_abs [m]", "tolerance_rel"],
        );
        refused(
            &with("tolerance_abs = 1e-3", "tolerance_abs = 1e-3\ntolerance_rel = 1e-2"),
            "reference.values[0].tolerance_rel",
            &["exactly one"],
        );
        refused(&with("tolerance_abs = 1e-3", "tolerance_abs = 0"), "reference.values[0].tolerance_abs", &["> 0"]);
        refused(
            &with("value = \"-0.5*L\"\ntolerance_abs = 1e-3", "value = 0\ntolerance_rel = 0.1"),
            "reference.values[0].tolerance_rel",
            &["tolerance_abs"],
        );
        refused(&with("value = \"-0.5*L\"", "value = \"-0.5*Q\""), "reference.values[0].value", &["Q"]);
        refused(&format!("{CASE}{ROW}{ROW}"), "reference.values[1].quantity", &["given twice", "reference.values[0]"]);
        match parse(&with("source", "sauce = 1\nsource")) {
            Err(CaseError::Syntax { message, .. }) => assert!(message.contains("sauce"), "{message}"),
            other => panic!("{other:?}"),
        }
    }

    /// `[reference.short]`: the keys of `cosserat sweep --set`, applied and validated as a
    /// whole by `Case::short_variant`.
    #[test]
    fn the_short_variant_sets_sweep_keys() {
        let c = parse(&format!("{CASE}{ROW}\n[reference.short]\nelements = 4\n")).unwrap();
        assert_eq!(c.checks.published.short, vec![("elements".to_string(), Setting::Number(4.0))]);
        let s = c.short_variant().unwrap().expect("a variant");
        assert_eq!((s.mesh.elements, c.mesh.elements, s.name.as_str()), (4, 10, "t (short)"));
        assert_eq!(s.checks.published, c.checks.published);
        refused(
            &format!("{CASE}{ROW}\n[reference.short]\nsteps = 4\n"),
            "reference.short.steps",
            &["elements", "continuation_steps"],
        );
        refused(&format!("{CASE}\n[reference.short]\nelements = 4\n"), "reference.short", &["published values"]);
        let bad = parse(&format!("{CASE}{ROW}\n[reference.short]\nelements = 1\n")).unwrap();
        let e = bad.short_variant().unwrap_err().to_string();
        assert!(e.contains("at least 2 elements"), "{e}");
    }

    /// A clip has no single final state to check.
    #[test]
    fn a_clip_case_takes_no_published_values() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases");
        let text = std::fs::read_to_string(dir.join("worm_roll_3d.toml")).unwrap();
        let e = Case::from_toml(&format!("{text}{ROW}"), "roll", &dir.join("worm_roll_3d.toml")).unwrap_err();
        assert!(matches!(&e, CaseError::Invalid { key, .. } if key == "reference.values"), "{e}");
        assert!(e.to_string().contains("no single final state"), "{e}");
    }
}
