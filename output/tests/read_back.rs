//! The output read back: the CSV by this test against the world's own columns, and the VTK
//! files by an independent reader, VTK's own (Python `vtk` package: `vtkXMLPolyDataReader`),
//! against the CSV. `.ci/run` installs the package and sets `MPM_REQUIRE_VTK`; without both
//! the VTK half is skipped with a note.

use mpm_gimp::{
    Dimension, Effects, HeapBuffer, MaterialDef, Real, Transfer, Transport, Vec3, World, WorldDef,
};
use mpm_gimp_output::{columns, write_csv, Series, Values};
use std::path::PathBuf;
use std::process::Command;

/// A world of `dim` with a moving, stressed block, APIC, particle forces, heat (and, in the
/// axisymmetric form, the hoop stretch), stepped a few times so every column has values.
fn scene(dim: Dimension, buf: &mut Option<HeapBuffer>) -> World<'_> {
    let def = WorldDef {
        dimension: dim,
        cells: if dim == Dimension::ThreeD {
            [12, 12, 12]
        } else {
            [16, 16, 1]
        },
        cell_size: 0.1,
        origin: if dim == Dimension::Axisymmetric2D {
            Vec3::new(-0.1, 0.0, 0.0)
        } else {
            Vec3::ZERO
        },
        transfer: Transfer::Apic,
        effects: Effects {
            particle_forces: true,
            heat: Some(Transport::INSULATED),
            ..Effects::NONE
        },
        ..WorldDef::DEFAULT
    };
    let bytes = mpm_gimp::memory_requirements(&def).unwrap().bytes;
    let buf = buf.insert(HeapBuffer::new(bytes));
    let mut w = World::init(&def, buf.as_mut_bytes()).unwrap();
    let material = MaterialDef {
        heat_capacity: 1000.0,
        conductivity: 10.0,
        ..MaterialDef::DEFAULT
    };
    let m = w.add_material(&material).unwrap();
    let ids = w
        .fill_box(
            Vec3::new(0.3, 0.3, 0.3),
            Vec3::new(0.7, 0.6, 0.6),
            m,
            Vec3::new(0.5, -0.2, 0.1),
        )
        .unwrap();
    let n = ids.len();
    let t: Vec<Real> = (0..n).map(|i| 300.0 + i as Real).collect();
    w.set_particle_scalar(mpm_gimp::ScalarField::Temperature, 0, &t)
        .unwrap();
    let f: Vec<Real> = (0..n).map(|i| 0.01 * (i % 7) as Real).collect();
    w.set_particle_forces(0, [&f, &f, if dim == Dimension::ThreeD { &f } else { &[] }])
        .unwrap();
    for _ in 0..5 {
        w.step(2.0e-3).unwrap();
    }
    w
}

fn scratch_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mpm-gimp-output-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The CSV holds every column, every value exactly (shortest round-trip text), and the
/// columns are the world's: checked against the particle view for the position pair, the
/// velocity, the material, `J`, the Cauchy stress `rho0 tau / J` and the temperature.
#[test]
fn csv_reads_back_to_the_worlds_columns() {
    for dim in [
        Dimension::Plane2D,
        Dimension::Axisymmetric2D,
        Dimension::ThreeD,
    ] {
        let mut buf = None;
        let w = scene(dim, &mut buf);
        let mut csv = Vec::new();
        write_csv(&mut csv, &w).unwrap();
        let text = String::from_utf8(csv).unwrap();
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let rows: Vec<Vec<f64>> = lines
            .map(|l| l.split(',').map(|x| x.parse::<f64>().unwrap()).collect())
            .collect();
        let v = w.particles();
        assert_eq!(rows.len(), v.count, "{dim:?}");
        let at = |name: &str| {
            header
                .iter()
                .position(|h| *h == name)
                .unwrap_or_else(|| panic!("{dim:?}: no column {name}"))
        };
        // Every column of `columns` in order, exactly.
        let mut k = 0;
        for col in columns(&w) {
            let width = col.components.len().max(1);
            for (i, row) in rows.iter().enumerate() {
                for c in 0..width {
                    let want = match &col.values {
                        Values::Float(x) => x[i * width + c],
                        Values::Int(x) => x[i * width + c] as f64,
                    };
                    assert_eq!(row[k + c], want, "{dim:?} {} {c} particle {i}", col.name);
                }
            }
            k += width;
        }
        assert_eq!(k, header.len());
        let d = if dim == Dimension::ThreeD { 3 } else { 2 };
        let rho0 = w.material(0).unwrap().density as f64;
        for (i, row) in rows.iter().enumerate() {
            for (a, axis) in ["x", "y", "z"].iter().enumerate().take(d) {
                let x = v.position[a][i] as f64 + v.position_low[a][i] as f64;
                assert_eq!(row[at(&format!("position_{axis}"))], x);
                assert_eq!(
                    row[at(&format!("velocity_{axis}"))],
                    v.velocity[a][i] as f64
                );
            }
            assert_eq!(row[at("material")], v.material[i] as f64);
            let j = v.jacobian(i) as f64;
            assert_eq!(row[at("J")], j);
            let xy = if d == 2 { 2 } else { 3 };
            assert_eq!(row[at("stress_xy")], v.stress[xy][i] as f64 * rho0 / j);
            assert_eq!(row[at("temperature")], v.temperature[i] as f64);
        }
        for name in ["force_x", "apic_moment_xy", "grid_temperature"] {
            at(name);
        }
        if dim == Dimension::Axisymmetric2D {
            at("hoop_stretch");
        }
    }
}

/// The `.vtp` frames and the `.pvd` series, read by VTK's own reader (an independent
/// implementation of the format): every array has the CSV's values, the points are the
/// positions, and the series lists the frames with their times.
#[test]
fn vtk_files_read_back_with_vtks_own_reader() {
    let python = Command::new("python3")
        .args(["-c", "import vtkmodules.vtkIOXML"])
        .status()
        .is_ok_and(|s| s.success());
    if !python {
        assert!(
            std::env::var_os("MPM_REQUIRE_VTK").is_none(),
            "MPM_REQUIRE_VTK is set but python3 cannot import vtk"
        );
        eprintln!("skipped: python3 with the vtk package is needed (pip install vtk)");
        return;
    }
    for dim in [Dimension::Plane2D, Dimension::ThreeD] {
        let dir = scratch_dir(&format!("{dim:?}"));
        let mut buf = None;
        let mut w = scene(dim, &mut buf);
        let mut series = Series::new(&dir, "scene").unwrap();
        let mut frames = vec![];
        for _ in 0..2 {
            let frame = series.write_frame(&w).unwrap();
            let csv = frame.with_extension("csv");
            write_csv(std::fs::File::create(&csv).unwrap(), &w).unwrap();
            frames.push((w.time(), frame, csv));
            w.step(2.0e-3).unwrap();
        }
        let mut script = String::from(SCRIPT);
        script.push_str(&format!(
            "check_series({:?}, [",
            series.pvd_path().to_str().unwrap()
        ));
        for (time, vtp, csv) in &frames {
            script.push_str(&format!(
                "({time:?}, {:?}, {:?}),",
                vtp.to_str().unwrap(),
                csv.to_str().unwrap()
            ));
        }
        script.push_str("])\n");
        let out = Command::new("python3")
            .args(["-c", &script])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{dim:?}: {}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}

const SCRIPT: &str = r#"
import csv, os, sys
import xml.etree.ElementTree as ET
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader

def fail(why):
    print(why)
    sys.exit(1)

def check_frame(vtp, csv_path):
    reader = vtkXMLPolyDataReader()
    reader.SetFileName(vtp)
    reader.Update()
    poly = reader.GetOutput()
    with open(csv_path) as f:
        rows = list(csv.reader(f))
    header, rows = rows[0], [[float(x) for x in r] for r in rows[1:]]
    n = len(rows)
    if poly.GetNumberOfPoints() != n or poly.GetNumberOfVerts() != n:
        fail(f"{vtp}: {poly.GetNumberOfPoints()} points, {poly.GetNumberOfVerts()} vertices, csv {n}")
    col = {name: k for k, name in enumerate(header)}
    for i in range(n):
        p = poly.GetPoint(i)
        for a, axis in enumerate("xyz"):
            if p[a] != rows[i][col["position_" + axis]]:
                fail(f"{vtp}: point {i} axis {axis}: {p[a]} vs {rows[i][col['position_' + axis]]}")
    data = poly.GetPointData()
    names = [data.GetArrayName(k) for k in range(data.GetNumberOfArrays())]
    covered = set()
    for name in names:
        array = data.GetArray(name)
        m = array.GetNumberOfComponents()
        keys = [name] if m == 1 else [k for k in header if k.startswith(name + "_")][:m]
        if len(keys) != m:
            fail(f"{vtp}: array {name} has {m} components, csv {keys}")
        for i in range(n):
            t = array.GetTuple(i)
            for c, key in enumerate(keys):
                if t[c] != rows[i][col[key]]:
                    fail(f"{vtp}: {name}[{i}][{c}] = {t[c]}, csv {key} = {rows[i][col[key]]}")
        covered.update(keys)
    missing = [h for h in header if h not in covered]
    if missing:
        fail(f"{vtp}: csv columns not in the vtp: {missing}")

def check_series(pvd, frames):
    root = ET.parse(pvd).getroot()
    sets = root.findall("./Collection/DataSet")
    if len(sets) != len(frames):
        fail(f"{pvd}: {len(sets)} data sets, wrote {len(frames)}")
    for ds, (time, vtp, csv_path) in zip(sets, frames):
        if float(ds.get("timestep")) != time:
            fail(f"{pvd}: timestep {ds.get('timestep')} vs {time}")
        path = os.path.join(os.path.dirname(pvd), ds.get("file"))
        if os.path.abspath(path) != os.path.abspath(vtp):
            fail(f"{pvd}: file {path} vs {vtp}")
        check_frame(path, csv_path)
    print("ok")
"#;
