//! `Material "mix"`: two named materials mixed by `amount`, each version's way.
//!
//! ```text
//! Material "mix" "string namedmaterial1" "a" "string namedmaterial2" "b" "color amount" [.3 .3 .3]  # v3
//! Material "mix" "string materials" ["a" "b"] "float amount" .3                                  # v4
//! ```
//! pbrt-v3's BSDF holds both materials' lobes, the first's scaled by amount and the
//! second's by 1 − amount; pbrt-v4 takes the second material with probability amount at
//! each point, by a hash of the point. The render-ready scene resolves mixes, as it
//! holds their materials; a mix that reaches itself is an error.

use super::MaterialKind;
use super::params::{Resolver, TexValue, float, spectrum};
use crate::approx::Approx;
use crate::mitsuba::{MaterialExport, MaterialOut};
use crate::parser::error::Diagnostic;
use crate::parser::params::{ParamList, ParamType};
use crate::parser::source::Span;
use crate::values::{Range, Res};

pub const NAME: &str = "mix";

/// How `mix` combines its two materials.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MixRule {
    /// pbrt-v3 (`namedmaterial1`, `namedmaterial2`, spectrum `amount`): the BSDF holds
    /// both materials' lobes, the first's scaled by amount and the second's by
    /// 1 − amount.
    Blend,
    /// pbrt-v4 (`string materials [a b]`, float `amount`): each hit takes the second
    /// material with probability amount, else the first.
    Choose,
}

pub fn read(_ty: &str, p: &ParamList, at: Span, r: &mut dyn Resolver) -> Res<MaterialKind> {
    let names_at = |n: &str| p.named(n).map_or(at, |x| x.value_span);
    if let Some(list) = p.array("materials", ParamType::String)? {
        let names = list.strings();
        let [a, b] = names else {
            let msg = format!("mix needs two \"materials\", not {}", names.len());
            return Err(Diagnostic::error(list.value_span, msg));
        };
        let materials = [r.named_material(a, list.value_span)?, r.named_material(b, list.value_span)?];
        let amount = float(p, "amount", 0.5, Range::Any, r)?;
        return Ok(MaterialKind::Mix { materials, amount, rule: MixRule::Choose });
    }
    let named = |n: &str, r: &mut dyn Resolver| -> Res<u32> {
        let name = p.string(n)?.ok_or_else(|| Diagnostic::error(at, format!("mix needs \"string {n}\"")))?;
        r.named_material(&name, names_at(n))
    };
    let materials = [named("namedmaterial1", r)?, named("namedmaterial2", r)?];
    let amount: TexValue = spectrum(p, "amount", 0.5, r)?;
    if materials.iter().any(|&m| r.material_type(m).is_some_and(|t| super::coated::NAMES.contains(&t))) {
        r.approximate(at, "pbrt-v4 coated material in a pbrt-v3 mix".into(), Approx::CoatInBlend);
    }
    if materials.iter().any(|&m| r.material_type(m) == Some(super::hair::NAME)) {
        r.approximate(at, "hair in a pbrt-v3 mix".into(), Approx::HairInBlend);
    }
    Ok(MaterialKind::Mix { materials, amount, rule: MixRule::Blend })
}

pub fn mitsuba(e: &mut dyn MaterialExport) -> MaterialOut {
    e.note("mix: no Mitsuba equivalent is exported yet; exported as grey diffuse");
    MaterialOut::Diffuse { reflectance: [0.5; 3] }
}
