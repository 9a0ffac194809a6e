//! The checks of a `[[mesh]]` part: the keys its generator takes, the bounds of its
//! coordinates and sizes, and each generator's parameters, turned into a [`PartSource`] (the
//! generator call with the checked parameters, or the Gmsh file) that the mesh assembly
//! (`super::mesh`) runs without further checks.

use crate::fe::ElementType;
use crate::io::case_file::MeshPart;
use crate::mesh::{generate, Mesh};
use crate::{within_bounds, MAX_MAGNITUDE};

use super::checks::{given, MAX_GENERATED_ELEMENTS, MAX_GRADING, MIN_GRADING};

/// A generator with its checked parameters, called with the body name.
pub(super) type Generator = Box<dyn FnOnce(&str) -> Mesh>;

/// A checked mesh part: what to generate or read.
pub(super) enum PartSource<'a> {
    Generator(Generator),
    /// A Gmsh file, relative to the case file.
    Gmsh(&'a str),
}

/// Checks part `p` (`key` = `mesh[i]`): first what every part shares (bounds, keys, size),
/// then its generator's parameters, last (generated parts) `distort`.
pub(super) fn check_part<'a>(p: &'a MeshPart, key: &str) -> Result<PartSource<'a>, String> {
    check_common(p, key)?;
    let part = Part { p, key };
    let generator = match p.generator.as_str() {
        "box" => part.box_generator()?,
        "beam" => part.beam_generator()?,
        "thick_sphere_octant" => part.sphere_octant_generator()?,
        "hemisphere_quarter" => part.hemisphere_generator()?,
        "gmsh" => {
            let file = p
                .file
                .as_deref()
                .ok_or_else(|| format!("{key}.file is required for gmsh"))?;
            return Ok(PartSource::Gmsh(file));
        }
        g => {
            return Err(format!(
                "{key}.generator = \"{g}\": must be box, beam, thick_sphere_octant, hemisphere_quarter or gmsh"
            ))
        }
    };
    if p.distort != 0.0 && !(0.0..0.3).contains(&p.distort) {
        return Err(format!(
            "{key}.distort = {}: must be in [0, 0.3)",
            p.distort
        ));
    }
    Ok(PartSource::Generator(generator))
}

/// The checks of every part: finite coordinates, a finite `distort`, at most
/// [`MAX_GENERATED_ELEMENTS`] hexahedra, only the keys of its generator, `file` only for gmsh.
fn check_common(p: &MeshPart, key: &str) -> Result<(), String> {
    for (name, v) in [("lo", p.lo), ("hi", p.hi), ("translate", p.translate)] {
        if let Some(v) = v {
            if !v.iter().all(|&c| within_bounds(c)) {
                return Err(format!(
                    "{key}.{name} = {v:?}: must be finite and within +-{MAX_MAGNITUDE:e}"
                ));
            }
        }
    }
    if !p.distort.is_finite() {
        return Err(format!("{key}.distort must be finite"));
    }
    let count = match (p.generator.as_str(), p.divisions, p.n_circ, p.n_rad) {
        ("box" | "beam", Some(d), _, _) => d.iter().map(|&v| v as f64).product::<f64>(),
        ("thick_sphere_octant", _, Some(c), Some(r)) => 3.0 * (c as f64).powi(2) * r as f64,
        ("hemisphere_quarter", _, Some(c), Some(r)) => {
            (c as f64).powi(3) + 3.0 * (c as f64).powi(2) * r as f64
        }
        _ => 0.0,
    };
    if count > MAX_GENERATED_ELEMENTS as f64 {
        return Err(format!(
            "{key}: {count:.0} hexahedra requested; at most {MAX_GENERATED_ELEMENTS}"
        ));
    }
    check_keys_apply(p, key)?;
    if p.generator != "gmsh" && p.file.is_some() {
        return Err(format!("{key}.file is only for generator \"gmsh\""));
    }
    Ok(())
}

/// The keys each generator takes.
fn keys_of(generator: &str) -> Option<&'static [&'static str]> {
    Some(match generator {
        "box" => &[
            "body",
            "element",
            "divisions",
            "lo",
            "hi",
            "grading",
            "grading_zone",
            "distort",
        ],
        "beam" => &[
            "body",
            "element",
            "divisions",
            "length",
            "width",
            "height",
            "distort",
        ],
        "thick_sphere_octant" => &[
            "body",
            "element",
            "n_circ",
            "n_rad",
            "inner_radius",
            "outer_radius",
            "distort",
        ],
        "hemisphere_quarter" => &[
            "body",
            "element",
            "n_circ",
            "n_rad",
            "radius",
            "pole_grading",
            "pole_zone",
            "radial_grading",
            "distort",
        ],
        "gmsh" => &["file"],
        _ => return None,
    })
}

/// Rejects keys that the part's generator does not use (they would be silently ignored).
fn check_keys_apply(p: &MeshPart, key: &str) -> Result<(), String> {
    let mut given = given!(p; element, divisions, lo, hi, grading, grading_zone, pole_zone,
        radius, pole_grading, radial_grading, length, width, height, n_circ, n_rad,
        inner_radius, outer_radius, file, body)
    .to_vec();
    given.push(("distort", p.distort != 0.0));
    // The unknown generator is reported by the caller.
    let Some(allowed) = keys_of(&p.generator) else {
        return Ok(());
    };
    match given.iter().find(|(k, set)| *set && !allowed.contains(k)) {
        Some((k, _)) => Err(format!(
            "{key}.{k} does not apply to generator \"{}\" (it takes: {})",
            p.generator,
            allowed.join(", ")
        )),
        None => Ok(()),
    }
}

/// A part and its key, for the checks of its generator's parameters.
struct Part<'a> {
    p: &'a MeshPart,
    key: &'a str,
}

impl Part<'_> {
    /// A parameter the generator requires.
    fn need<T>(&self, v: Option<T>, name: &str) -> Result<T, String> {
        v.ok_or_else(|| {
            format!(
                "{}.{name} is required for generator \"{}\"",
                self.key, self.p.generator
            )
        })
    }

    /// `v` when `ok`, else the message that parameter `name` (= `v`) must be `what`.
    fn must_be(&self, name: &str, v: f64, ok: bool, what: &str) -> Result<f64, String> {
        if ok {
            Ok(v)
        } else {
            Err(format!("{}.{name} = {v}: must be {what}", self.key))
        }
    }

    /// A required length: positive and at most `MAX_MAGNITUDE`.
    fn length(&self, v: Option<f64>, name: &str) -> Result<f64, String> {
        let v = self.need(v, name)?;
        let what = format!("> 0 and at most {MAX_MAGNITUDE:e}");
        self.must_be(name, v, v > 0.0 && within_bounds(v), &what)
    }

    /// The element type.
    fn element(&self) -> Result<ElementType, String> {
        let key = self.key;
        let name = self
            .p
            .element
            .as_deref()
            .ok_or_else(|| format!("{key}.element is required"))?;
        ElementType::from_name(name).ok_or_else(|| {
            format!("{key}.element = \"{name}\": must be hex8, hex20, hex27, tet4 or tet10")
        })
    }

    /// The divisions of a box or beam, each >= 1.
    fn divisions(&self) -> Result<[usize; 3], String> {
        let key = self.key;
        let d = self
            .p
            .divisions
            .ok_or_else(|| format!("{key}.divisions is required"))?;
        if d.contains(&0) {
            return Err(format!("{key}.divisions = {d:?}: every entry must be >= 1"));
        }
        Ok(d)
    }

    /// The sphere generators' `n_circ` and `n_rad`: required, >= 1.
    fn sphere_cells(&self) -> Result<(usize, usize), String> {
        let nc = self.need(self.p.n_circ, "n_circ")?;
        let nr = self.need(self.p.n_rad, "n_rad")?;
        if nc == 0 || nr == 0 {
            return Err(format!("{}: n_circ and n_rad must be >= 1", self.key));
        }
        Ok((nc, nr))
    }

    /// The box: `lo` below `hi`, gradings within bounds, zones inside the box on graded axes.
    fn box_generator(&self) -> Result<Generator, String> {
        let (p, key) = (self.p, self.key);
        let lo = p.lo.ok_or_else(|| format!("{key}.lo is required"))?;
        let hi = p.hi.ok_or_else(|| format!("{key}.hi is required"))?;
        if (0..3).any(|d| hi[d] <= lo[d]) {
            return Err(format!(
                "{key}: hi {hi:?} must exceed lo {lo:?} in every axis"
            ));
        }
        let grading = p.grading.unwrap_or([1.0; 3]);
        if let Some(g) = grading
            .iter()
            .find(|g| !(**g >= MIN_GRADING && **g <= MAX_GRADING))
        {
            return Err(format!(
                "{key}.grading = {grading:?}: every entry must be in [{MIN_GRADING:e}, \
                 {MAX_GRADING:e}] (got {g})"
            ));
        }
        let zone = p.grading_zone.unwrap_or([0.0; 3]);
        for d in 0..3 {
            if !(zone[d] >= 0.0 && zone[d] < hi[d] - lo[d]) {
                return Err(format!(
                    "{key}.grading_zone = {zone:?}: every entry must be >= 0 and below the \
                     box's length along its axis"
                ));
            }
            if zone[d] > 0.0 && grading[d] == 1.0 {
                return Err(format!(
                    "{key}.grading_zone = {zone:?}: axis {d} has a zone but no grading \
                     (grading[{d}] = 1)"
                ));
            }
        }
        let (element, divisions) = (self.element()?, self.divisions()?);
        Ok(Box::new(move |body| {
            generate::zoned_box_mesh(element, divisions, lo, hi, grading, zone, body)
        }))
    }

    /// The beam: positive lengths.
    fn beam_generator(&self) -> Result<Generator, String> {
        let (element, divisions) = (self.element()?, self.divisions()?);
        let length = self.length(self.p.length, "length")?;
        let width = self.length(self.p.width, "width")?;
        let height = self.length(self.p.height, "height")?;
        Ok(Box::new(move |body| {
            generate::beam(element, divisions, length, width, height, body)
        }))
    }

    /// The thick sphere octant: `0 < inner_radius < outer_radius`.
    fn sphere_octant_generator(&self) -> Result<Generator, String> {
        let a = self.length(self.p.inner_radius, "inner_radius")?;
        let b = self.length(self.p.outer_radius, "outer_radius")?;
        if b <= a {
            return Err(format!(
                "{}: outer_radius {b} must exceed inner_radius {a}",
                self.key
            ));
        }
        let (nc, nr) = self.sphere_cells()?;
        let element = self.element()?;
        Ok(Box::new(move |body| {
            generate::thick_sphere_octant(element, nc, nr, a, b, body)
        }))
    }

    /// A hemisphere grading (default 1): in `[1, MAX_GRADING]`.
    fn hemisphere_grading(&self, v: Option<f64>, name: &str) -> Result<f64, String> {
        let g = v.unwrap_or(1.0);
        let what = format!("in [1, {MAX_GRADING:e}]");
        self.must_be(name, g, (1.0..=MAX_GRADING).contains(&g), &what)
    }

    /// The quarter hemisphere: hexahedra, gradings within bounds, a pole zone only with a pole
    /// grading and shorter than 0.9 of the quarter meridian.
    fn hemisphere_generator(&self) -> Result<Generator, String> {
        let (p, key) = (self.p, self.key);
        let r = self.length(p.radius, "radius")?;
        let (nc, nr) = self.sphere_cells()?;
        let pole = self.hemisphere_grading(p.pole_grading, "pole_grading")?;
        let radial = self.hemisphere_grading(p.radial_grading, "radial_grading")?;
        let element = self.element()?;
        if !element.is_hex() {
            return Err(format!(
                "{key}.element = \"{}\": generator \"hemisphere_quarter\" makes hexahedra \
                 (hex8, hex20 or hex27)",
                element.name()
            ));
        }
        let zone = p.pole_zone.unwrap_or(0.0);
        if !(zone >= 0.0 && zone < 0.9 * std::f64::consts::FRAC_PI_2 * r) {
            return Err(format!(
                "{key}.pole_zone = {zone}: must be >= 0 and below 0.9 pi R / 2 (an arc \
                 length on the sphere)"
            ));
        }
        if zone > 0.0 && pole == 1.0 {
            return Err(format!(
                "{key}.pole_zone = {zone}: has no effect without pole_grading > 1"
            ));
        }
        Ok(Box::new(move |body| {
            generate::hemisphere_quarter(element, nc, nr, r, pole, zone, radial, body)
        }))
    }
}
