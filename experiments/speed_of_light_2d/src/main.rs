mod check;
mod fast;
mod reference;
mod scene;

use scene::*;
use std::time::{Duration, Instant};

enum Proto {
    Ref(reference::Reference),
    Fast(fast::Fast),
}

impl Proto {
    fn step(&mut self, p: &Params, usl: bool) {
        match self {
            Proto::Ref(r) => r.step(p, usl),
            Proto::Fast(f) => f.step(p, usl),
        }
    }
    fn v2max(&self) -> f64 {
        match self {
            Proto::Ref(r) => (0..r.n)
                .map(|i| (r.v[0][i] as f64).powi(2) + (r.v[1][i] as f64).powi(2))
                .fold(0.0, f64::max),
            Proto::Fast(f) => f.v2max as f64,
        }
    }
    fn state(&self) -> check::State {
        match self {
            Proto::Ref(r) => check::State {
                x: r.x.clone(),
                v: r.v.clone(),
                tau: r.tau.clone(),
            },
            Proto::Fast(f) => {
                let n = f.n;
                let un = |c: &Vec<f32>| {
                    let mut o = vec![0.0f32; n];
                    for i in 0..n {
                        o[f.id[i] as usize] = c[i];
                    }
                    o
                };
                check::State {
                    x: [un(&f.x), un(&f.y)],
                    v: [un(&f.vx), un(&f.vy)],
                    tau: [un(&f.txx), un(&f.tyy), un(&f.txy), un(&f.tzz)],
                }
            }
        }
    }
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

fn main() {
    let mut runs = 7u32;
    let mut steps = 10u32;
    let mut usl = false;
    let mut variant = "fast".to_string();
    let mut opts = fast::Opts {
        fma: true,
        stored: true,
        binned: true,
        checks: false,
        breakdown: false,
        skip: 0,
        fission: true,
        compact: true,
        split: true,
        gcache: true,
    };
    let mut do_check = false;
    let mut resort_test = false;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let (k, inline) = match a.split_once('=') {
            Some((k, v)) if k.starts_with("--") => (k.to_string(), Some(v.to_string())),
            _ => (a.clone(), None),
        };
        let mut val = || inline.clone().or_else(|| args.next()).expect("value");
        match k.as_str() {
            "--runs" => runs = val().parse().unwrap(),
            "--steps" => steps = val().parse().unwrap(),
            "--dim" => {
                let _ = val();
            }
            "--order" => usl = val() == "usl",
            "--variant" => variant = val(),
            "--nofma" => opts.fma = false,
            "--nostore" => opts.stored = false,
            "--nobin" => opts.binned = false,
            "--nofission" => opts.fission = false,
            "--nocompact" => opts.compact = false,
            "--nosplit" => opts.split = false,
            "--nogcache" => opts.gcache = false,
            "--checks" => opts.checks = true,
            "--breakdown" => opts.breakdown = true,
            "--check" => do_check = true,
            "--skip" => opts.skip = val().parse().unwrap(),
            "--resort-test" => resort_test = true,
            _ => {
                eprintln!("sol: unknown option {a}");
                std::process::exit(2);
            }
        }
    }
    let mut p = Params::new();
    let init = initial(&p);
    let n = init.x.len();
    let p0 = p;
    let make = |variant: &str, opts: fast::Opts| -> Proto {
        match variant {
            "ref" => Proto::Ref(reference::Reference::new(&init)),
            _ => Proto::Fast(fast::Fast::new(&init, &p0, opts)),
        }
    };

    if do_check {
        let mut k = check::Kernel::new(usl);
        let mut protos = vec![("ref", make("ref", opts)), ("fast", make(&variant, opts))];
        let s0 = k.state();
        for (name, pr) in protos.iter() {
            let c = check::compare(&pr.state(), &s0, p.inv_h);
            eprintln!("initial {name}: dx {:.3e} cells", c.0);
        }
        for step in 0..10 {
            let dt = k.world().stable_dt();
            let own = p.stable_dt(protos[0].1.v2max());
            let r = k.world().step(dt).unwrap();
            assert_eq!(r.frozen, 0);
            p.dt = dt;
            for (_, pr) in protos.iter_mut() {
                pr.step(&p, usl);
            }
            let ks = k.state();
            for (name, pr) in protos.iter() {
                let c = check::compare(&pr.state(), &ks, p.inv_h);
                eprintln!(
                    "step {step} {name}: dt {dt:.6e} (own {own:.6e}) max|dx| {:.3e} cells, max|dv|/max|v| {:.3e}, max|dtau|/max|tau| {:.3e} (max |tau| {:.4e})",
                    c.0, c.1, c.2, c.3
                );
            }
        }
        {
            let mut o2 = opts;
            o2.split = !opts.split;
            let mut other = make(&variant, o2);
            let mut q = make(&variant, opts);
            let mut p2 = Params::new();
            p2.dt = 1.3e-4;
            for _ in 0..10 {
                other.step(&p2, usl);
                q.step(&p2, usl);
            }
            let c = check::compare(&other.state(), &q.state(), p2.inv_h);
            eprintln!(
                "fast vs fast with split toggled: dx {:.3e} dv {:.3e} dtau {:.3e}",
                c.0, c.1, c.2
            );
        }
        if let Proto::Fast(f) = &protos[1].1 {
            eprintln!("fast: moved {} bad {}", f.moved, f.bad);
        }
        return;
    }

    let mut proto = make(&variant, opts);
    if resort_test {
        if let Proto::Fast(f) = &mut proto {
            let t0 = Instant::now();
            for _ in 0..10 {
                f.resort(&p);
            }
            eprintln!(
                "resort: {:.3} ns per particle",
                t0.elapsed().as_nanos() as f64 / (10.0 * n as f64)
            );
        }
    }
    // Timing as benches/common/timing.rs: 3 warm-up steps, then runs of `steps` steps; only the
    // step is timed; dt from the fastest particle (tracked by the particle pass).
    let step = |proto: &mut Proto, p: &mut Params| -> Duration {
        p.dt = p.stable_dt(proto.v2max().max(0.01));
        let t0 = Instant::now();
        proto.step(p, usl);
        t0.elapsed()
    };
    for _ in 0..3 {
        step(&mut proto, &mut p);
    }
    if let Proto::Fast(f) = &mut proto {
        f.times = [0.0; 6];
    }
    let mut times = Vec::new();
    for _ in 0..runs {
        let mut e = Duration::ZERO;
        for _ in 0..steps {
            e += step(&mut proto, &mut p);
        }
        times.push(e.as_nanos() as f64 / (steps as f64 * n as f64));
    }
    let med = median(&times);
    let runs_json = times
        .iter()
        .map(|r| format!("{r:.3}"))
        .collect::<Vec<_>>()
        .join(",");
    let mut extra = String::new();
    if let Proto::Fast(f) = &proto {
        if opts.breakdown {
            let total = (runs * steps) as f64 * n as f64;
            let names = ["reset", "scatter", "grid1", "particles", "grid2", "stress"];
            let parts: Vec<String> = names
                .iter()
                .zip(f.times.iter())
                .map(|(nm, t)| format!("\"{nm}\":{:.3}", t * 1e9 / total))
                .collect();
            extra = format!(",\"breakdown\":{{{}}}", parts.join(","));
        }
        extra += &format!(",\"moved\":{},\"bad\":{}", f.moved, f.bad);
    }
    println!(
        "{{\"variant\":\"{variant}\",\"order\":\"{}\",\"opts\":\"{:?}\",\"particles\":{n},\"ns_per_particle_step\":{med:.3},\"runs\":[{runs_json}]{extra}}}",
        if usl { "usl" } else { "musl" },
        opts
    );
}
