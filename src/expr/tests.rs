//! Parser, evaluation, compilation and FreeFEM output of expressions.
use super::*;

fn ev(src: &str) -> f64 {
    Expr::parse(src)
        .expect("parse")
        .eval(&|n| match n {
            "x" => Some(0.3),
            "y" => Some(-1.7),
            "s" => Some(0.25),
            "t" => Some(0.01),
            _ => None,
        })
        .expect("eval")
}

#[test]
fn precedence_and_associativity() {
    assert_eq!(ev("1+2*3"), 7.0);
    assert_eq!(ev("(1+2)*3"), 9.0);
    assert_eq!(ev("8/4/2"), 1.0);
    assert_eq!(ev("8-4-2"), 2.0);
    assert_eq!(ev("2^3^2"), 512.0);
    assert_eq!(ev("2*3^2"), 18.0);
    assert_eq!(ev("-2^2"), -4.0);
    assert_eq!(ev("(-2)^2"), 4.0);
    assert_eq!(ev("2^-1"), 0.5);
    assert_eq!(ev("--3"), 3.0);
    assert_eq!(ev("+3 - -2"), 5.0);
    assert_eq!(ev("-x*y"), -0.3 * -1.7);
    assert_eq!(ev("1e-3 + .5 + 2. + 2E+1"), 1e-3 + 0.5 + 2.0 + 20.0);
    assert_eq!(ev("pi"), std::f64::consts::PI);
}

#[test]
fn every_function() {
    let x: f64 = 0.3;
    let cases: [(&str, f64); 17] = [
        ("sin(x)", x.sin()),
        ("cos(x)", x.cos()),
        ("tan(x)", x.tan()),
        ("exp(x)", x.exp()),
        ("log(x)", x.ln()),
        ("sqrt(x)", x.sqrt()),
        ("abs(y)", 1.7),
        ("sinh(x)", x.sinh()),
        ("cosh(x)", x.cosh()),
        ("tanh(x)", x.tanh()),
        ("atan(x)", x.atan()),
        ("asin(x)", x.asin()),
        ("acos(x)", x.acos()),
        ("pow(x,y)", x.powf(-1.7)),
        ("atan2(y,x)", (-1.7f64).atan2(x)),
        ("min(x,y)", -1.7),
        ("max(x,y)", x),
    ];
    for (src, want) in cases {
        assert_eq!(ev(src), want, "{src}");
    }
    // Non-finite results are not errors.
    assert!(ev("log(y)").is_nan());
    assert_eq!(ev("1/0"), f64::INFINITY);
}

#[test]
fn errors_with_positions() {
    let e = Expr::parse("(1+2))").unwrap_err();
    assert_eq!(e.to_string(), "unexpected ')' at column 6, expected an operator or end of input");
    let e = Expr::parse("sin(1+)").unwrap_err();
    assert!(matches!(e, ExprError::Unexpected { column: 7, .. }), "{e}");
    assert!(e.to_string().starts_with("unexpected ')' at column 7"));
    assert_eq!(Expr::parse("2*sinn(s)").unwrap_err(), ExprError::UnknownFunction { name: "sinn".into(), column: 3 });
    assert_eq!(Expr::parse("2*sinn(s)").unwrap_err().to_string(), "unknown function 'sinn' at column 3");
    assert!(matches!(Expr::parse("pow(1)"), Err(ExprError::WrongArity { expected: 2, found: 1, .. })));
    assert!(matches!(Expr::parse("sin(1,2)"), Err(ExprError::WrongArity { expected: 1, found: 2, .. })));
    assert!(matches!(Expr::parse("1e"), Err(ExprError::InvalidNumber { column: 1, .. })));
    assert!(matches!(Expr::parse("1e999"), Err(ExprError::InvalidNumber { .. })));
    assert!(matches!(Expr::parse("  "), Err(ExprError::Empty)));
    assert!(matches!(Expr::parse("2 # 3"), Err(ExprError::InvalidCharacter { ch: '#', column: 3 })));
    assert!(matches!(Expr::parse("2*sin"), Err(ExprError::FunctionAsVariable { column: 3, .. })));
    assert!(matches!(Expr::parse("(1+2"), Err(ExprError::Unexpected { column: 5, .. })));
    assert!(matches!(Expr::parse("2 3"), Err(ExprError::Unexpected { column: 3, .. })));
    assert!(matches!(Expr::parse("*3"), Err(ExprError::Unexpected { column: 1, .. })));
    let e = Expr::parse("a+b").unwrap().eval(&|n| (n == "a").then_some(1.0)).unwrap_err();
    assert_eq!(e.to_string(), "unknown variable 'b'");
    assert_eq!(
        Expr::parse("a+b").unwrap().compile(&["a"]).unwrap_err(),
        ExprError::UnknownVariable { name: "b".into() }
    );
}

#[test]
fn variables_and_constants() {
    let e = Expr::parse("-Fmax*(exp(4*s/L0)-1)/3 + pi*t").unwrap();
    let v: Vec<_> = e.variables().into_iter().collect();
    assert_eq!(v, ["Fmax", "L0", "s", "t"]);
    let mut c = BTreeMap::new();
    c.insert("E".to_string(), 1.1e5);
    assert_eq!(eval_const("E/(2*(1+0.4))", &c).unwrap(), 1.1e5 / (2.0 * (1.0 + 0.4)));
    assert!(matches!(eval_const("E/G", &c), Err(ExprError::UnknownVariable { .. })));
    assert_eq!(Expr::parse("2*pi").unwrap().compile(&[]).unwrap().as_constant(), Some(2.0 * std::f64::consts::PI));
}

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn unif(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn pick(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

fn random_expr(r: &mut Rng, depth: u32) -> String {
    const VARS: [&str; 3] = ["a", "b", "c"];
    if depth == 0 || r.pick(4) == 0 {
        return match r.pick(3) {
            0 => format!("{}", (r.unif() * 10.0 * 1e3).round() / 1e3),
            1 => "pi".into(),
            _ => VARS[r.pick(3)].into(),
        };
    }
    let a = random_expr(r, depth - 1);
    let b = random_expr(r, depth - 1);
    match r.pick(8) {
        0 => format!("({a}+{b})"),
        1 => format!("{a}-{b}"),
        2 => format!("{a}*{b}"),
        3 => format!("({a})/({b})"),
        4 => format!("-{a}^2"),
        5 => format!("{}({a})", FUNC1[r.pick(FUNC1.len())].0),
        6 => format!("{}({a},{b})", FUNC2[r.pick(FUNC2.len())].0),
        _ => format!("({a})"),
    }
}

#[test]
fn compile_matches_eval_and_display_roundtrip() {
    let mut r = Rng(0x9E3779B97F4A7C15);
    for _ in 0..500 {
        let src = random_expr(&mut r, 5);
        let e = Expr::parse(&src).unwrap_or_else(|err| panic!("{src}: {err}"));
        let c = e.compile(&["a", "b", "c"]).unwrap();
        let again = Expr::parse(&e.to_string()).unwrap();
        for _ in 0..5 {
            let vals = [r.unif() * 4.0 - 2.0, r.unif() * 4.0 - 2.0, r.unif()];
            let x = e
                .eval(&|n| match n {
                    "a" => Some(vals[0]),
                    "b" => Some(vals[1]),
                    "c" => Some(vals[2]),
                    _ => None,
                })
                .unwrap();
            let y = c.eval(&vals);
            let z = again.compile(&["a", "b", "c"]).unwrap().eval(&vals);
            assert!(x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()), "{src}: {x} vs {y}");
            assert!(x.to_bits() == z.to_bits() || (x.is_nan() && z.is_nan()), "{src}: {x} vs {z}");
        }
    }
    // Too few slots: NaN instead of a panic.
    assert!(Expr::parse("a+b").unwrap().compile(&["a", "b"]).unwrap().eval(&[1.0]).is_nan());
}

#[test]
fn number_format_roundtrip() {
    let vals = [
        0.1,
        1.0 / 3.0,
        2.07e2,
        207.0236,
        5e-324,
        f64::MAX,
        f64::MIN_POSITIVE,
        1.1e5 / 2.8,
        std::f64::consts::PI,
        0.30000000000000004,
        123456789012345680.0,
        2e3,
    ];
    for v in vals {
        let s = format!("{v:e}");
        assert!(s.contains('e'), "{s}");
        assert_eq!(s.parse::<f64>().unwrap(), v, "{s}");
        let e = Expr::parse(&s).unwrap();
        assert_eq!(e.eval(&|_| None).unwrap(), v);
    }
}

#[test]
fn freefem_emitter() {
    let rename = |n: &str| match n {
        "s" => "S".to_string(),
        "t" => "T".to_string(),
        other => format!("k_{other}"),
    };
    let ff = |src: &str| Expr::parse(src).unwrap().to_freefem(&rename);
    assert_eq!(ff("2e3*sin(pi*s)*sin(8*omega0*t)"), "((2e3*sin((pi*S)))*sin(((8e0*k_omega0)*T)))");
    assert_eq!(ff("-F"), "(-k_F)");
    assert_eq!(ff("-Fmax*(exp(4*s/L0)-1)/3"), "(((-k_Fmax)*(exp(((4e0*S)/k_L0))-1e0))/3e0)");
    assert_eq!(ff("E/(2*(1+0.4))"), "(k_E/(2e0*(1e0+4e-1)))");
    assert_eq!(ff("-2^2 + atan2(s,t) + max(s, 1.5)"), "(((-pow(2e0,2e0))+atan2(S,T))+max(S,1.5e0))");
}

/// Nesting is bounded (no stack overflow on hostile input): a tree of exactly MAX_DEPTH levels
/// parses and round-trips through its fully parenthesised print, one more level is refused.
#[test]
fn nesting_is_bounded() {
    let sum = |terms: usize| vec!["1"; terms].join("+");
    let e = Expr::parse(&sum(MAX_DEPTH)).unwrap();
    assert_eq!(e.eval(&|_| None).unwrap(), MAX_DEPTH as f64);
    let again = Expr::parse(&e.to_string()).unwrap();
    assert_eq!(again, e);
    let e = Expr::parse(&sum(MAX_DEPTH + 1)).unwrap_err();
    assert_eq!(e.to_string(), format!("expression nested more than 200 levels deep at column {}", 2 * MAX_DEPTH + 2));
    let signs = format!("{}1", "-".repeat(MAX_DEPTH - 1));
    assert_eq!(Expr::parse(&signs).unwrap().eval(&|_| None).unwrap(), -1.0);
    let neg = Expr::parse(&signs).unwrap();
    assert_eq!(Expr::parse(&neg.to_string()).unwrap(), neg, "a sign chain's print re-parses");
    assert!(matches!(Expr::parse(&format!("-{signs}")), Err(ExprError::TooDeep { .. })));
    // Deep enough to overflow any stack if it were parsed recursively without a bound.
    for hostile in [format!("{}1", "(".repeat(1_000_000)), "+".repeat(1_000_000) + "1", sum(500_000)] {
        assert!(matches!(Expr::parse(&hostile), Err(ExprError::TooDeep { limit: MAX_DEPTH, .. })));
    }
    let calls = format!("{}s{}", "sin(".repeat(MAX_DEPTH), ")".repeat(MAX_DEPTH));
    assert!(matches!(Expr::parse(&calls), Err(ExprError::TooDeep { .. })));
}
