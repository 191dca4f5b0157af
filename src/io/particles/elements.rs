//! Element radii and colours: van der Waals radii from S. Alvarez, "A cartography of the van der Waals
//! territories", Dalton Trans. 42 (2013) 8617–8636 (elements it gives no radius get the fallback), and
//! Jmol's CPK colours. Values are in Å and 8-bit sRGB as published; docs/scene-format.md cites both.

use crate::math::Rgb;

/// Radius (Å) of an element the table has no radius for, and of an unknown element.
pub(crate) const FALLBACK_RADIUS: f64 = 1.5;

/// Colour of an unknown element: pink, #FF1493.
pub(crate) const FALLBACK_COLOR: u32 = 0xFF1493;

/// One element: symbol, van der Waals radius in Å (0 where Alvarez gives none), Jmol colour `0xRRGGBB`.
/// Atomic number Z is the index in [`ELEMENTS`] plus one.
pub(crate) type Element = (&'static str, f64, u32);

/// Elements H (Z = 1) to Cm (Z = 96), in order of atomic number.
#[rustfmt::skip]
pub(crate) const ELEMENTS: &[Element] = &[
    ("H", 1.20, 0xFFFFFF), ("He", 1.43, 0xD9FFFF), ("Li", 2.12, 0xCC80FF), ("Be", 1.98, 0xC2FF00),
    ("B", 1.91, 0xFFB5B5), ("C", 1.77, 0x909090), ("N", 1.66, 0x3050F8), ("O", 1.50, 0xFF0D0D),
    ("F", 1.46, 0x90E050), ("Ne", 1.58, 0xB3E3F5), ("Na", 2.50, 0xAB5CF2), ("Mg", 2.51, 0x8AFF00),
    ("Al", 2.25, 0xBFA6A6), ("Si", 2.19, 0xF0C8A0), ("P", 1.90, 0xFF8000), ("S", 1.89, 0xFFFF30),
    ("Cl", 1.82, 0x1FF01F), ("Ar", 1.83, 0x80D1E3), ("K", 2.73, 0x8F40D4), ("Ca", 2.62, 0x3DFF00),
    ("Sc", 2.58, 0xE6E6E6), ("Ti", 2.46, 0xBFC2C7), ("V", 2.42, 0xA6A6AB), ("Cr", 2.45, 0x8A99C7),
    ("Mn", 2.45, 0x9C7AC7), ("Fe", 2.44, 0xE06633), ("Co", 2.40, 0xF090A0), ("Ni", 2.40, 0x50D050),
    ("Cu", 2.38, 0xC88033), ("Zn", 2.39, 0x7D80B0), ("Ga", 2.32, 0xC28F8F), ("Ge", 2.29, 0x668F8F),
    ("As", 1.88, 0xBD80E3), ("Se", 1.82, 0xFFA100), ("Br", 1.86, 0xA62929), ("Kr", 2.25, 0x5CB8D1),
    ("Rb", 3.21, 0x702EB0), ("Sr", 2.84, 0x00FF00), ("Y", 2.75, 0x94FFFF), ("Zr", 2.52, 0x94E0E0),
    ("Nb", 2.56, 0x73C2C9), ("Mo", 2.45, 0x54B5B5), ("Tc", 2.44, 0x3B9E9E), ("Ru", 2.46, 0x248F8F),
    ("Rh", 2.44, 0x0A7D8C), ("Pd", 2.15, 0x006985), ("Ag", 2.53, 0xC0C0C0), ("Cd", 2.49, 0xFFD98F),
    ("In", 2.43, 0xA67573), ("Sn", 2.42, 0x668080), ("Sb", 2.47, 0x9E63B5), ("Te", 1.99, 0xD47A00),
    ("I", 2.04, 0x940094), ("Xe", 2.06, 0x429EB0), ("Cs", 3.48, 0x57178F), ("Ba", 3.03, 0x00C900),
    ("La", 2.98, 0x70D4FF), ("Ce", 2.88, 0xFFFFC7), ("Pr", 2.92, 0xD9FFC7), ("Nd", 2.95, 0xC7FFC7),
    ("Pm", 0.0, 0xA3FFC7), ("Sm", 2.90, 0x8FFFC7), ("Eu", 2.87, 0x61FFC7), ("Gd", 2.83, 0x45FFC7),
    ("Tb", 2.79, 0x30FFC7), ("Dy", 2.87, 0x1FFFC7), ("Ho", 2.81, 0x00FF9C), ("Er", 2.83, 0x00E675),
    ("Tm", 2.79, 0x00D452), ("Yb", 2.80, 0x00BF38), ("Lu", 2.74, 0x00AB24), ("Hf", 2.63, 0x4DC2FF),
    ("Ta", 2.53, 0x4DA6FF), ("W", 2.57, 0x2194D6), ("Re", 2.49, 0x267DAB), ("Os", 2.48, 0x266696),
    ("Ir", 2.41, 0x175487), ("Pt", 2.29, 0xD0D0E0), ("Au", 2.32, 0xFFD123), ("Hg", 2.45, 0xB8B8D0),
    ("Tl", 2.47, 0xA6544D), ("Pb", 2.60, 0x575961), ("Bi", 2.54, 0x9E4FB5), ("Po", 0.0, 0xAB5C00),
    ("At", 0.0, 0x754F45), ("Rn", 0.0, 0x428296), ("Fr", 0.0, 0x420066), ("Ra", 0.0, 0x007D00),
    ("Ac", 2.80, 0x70ABFA), ("Th", 2.93, 0x00BAFF), ("Pa", 2.88, 0x00A1FF), ("U", 2.71, 0x008FFF),
    ("Np", 2.82, 0x0080FF), ("Pu", 2.81, 0x006BFF), ("Am", 2.83, 0x545CF2), ("Cm", 3.05, 0x785CE3),
];

/// The element a symbol names, matched without regard to case (`CL`, `cl` and `Cl` are chlorine), or an
/// atomic number (`6` is carbon).
pub(crate) fn lookup(name: &str) -> Option<&'static Element> {
    if let Ok(z) = name.parse::<usize>() {
        return z.checked_sub(1).and_then(|i| ELEMENTS.get(i));
    }
    ELEMENTS.iter().find(|(symbol, _, _)| symbol.eq_ignore_ascii_case(name))
}

/// The element's radius in Å, if the table has one.
pub(crate) fn radius(element: &Element) -> Option<f64> {
    (element.1 > 0.0).then_some(element.1)
}

/// `0xRRGGBB` as a colour with channels in [0, 1].
pub(crate) fn rgb(hex: u32) -> Rgb {
    let channel = |shift: u32| ((hex >> shift) & 0xFF) as f32 / 255.0;
    Rgb::new(channel(16), channel(8), channel(0))
}

/// Residue names of water models (`TIP`: CHARMM's `TIP4` in PDB's three residue columns, its `4` falling in
/// the chain's).
const WATERS: [&str; 16] = [
    "HOH", "WAT", "SOL", "H2O", "SPC", "SPCE", "TIP", "TIP3", "TIP4", "TIP5", "TP3", "TP4", "TP5", "T3P",
    "T4P", "T5P",
];

/// The element of a PDB/GRO atom name (`CA`, `OW`, `HG21`, `1HB`, `NA`): the ion named as its residue
/// (`NA` in residue `NA`) or, when `two_letters` allows it, a known two-letter element written from the
/// name's first character; otherwise the name's first letter. None for CHARMM's TIP4P charge site `OM` in a
/// water residue, which is no oxygen.
pub(crate) fn from_atom_name(name: &str, residue: &str, two_letters: bool) -> Option<&'static Element> {
    let letters: String = name.trim().chars().filter(char::is_ascii_alphabetic).collect();
    if letters.is_empty() {
        return None;
    }
    if letters.eq_ignore_ascii_case("OM") && WATERS.iter().any(|w| w.eq_ignore_ascii_case(residue.trim())) {
        return None;
    }
    if letters.eq_ignore_ascii_case(residue.trim()) {
        if let Some(e) = lookup(&letters) {
            return Some(e);
        }
    }
    if two_letters && letters.len() >= 2 {
        if let Some(e) = lookup(&letters[..2]) {
            return Some(e);
        }
    }
    lookup(&letters[..1])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_numbers_index_the_table() {
        assert_eq!(ELEMENTS.len(), 96);
        assert_eq!(lookup("6").unwrap().0, "C");
        assert_eq!(lookup("92").unwrap().0, "U");
        assert_eq!(lookup("cl").unwrap().1, 1.82);
        assert!(lookup("0").is_none() && lookup("Xx").is_none());
        assert_eq!(radius(lookup("Po").unwrap()), None);
        assert_eq!(rgb(0xFF8000), Rgb::new(1.0, 128.0 / 255.0, 0.0));
    }

    #[test]
    fn atom_names_give_elements() {
        assert_eq!(from_atom_name(" CA ", "ALA", false).unwrap().0, "C");
        assert_eq!(from_atom_name("CA", "CA", false).unwrap().0, "Ca");
        assert_eq!(from_atom_name("FE", "HEM", true).unwrap().0, "Fe");
        assert_eq!(from_atom_name("HG21", "THR", false).unwrap().0, "H");
        assert_eq!(from_atom_name("1HB", "ALA", false).unwrap().0, "H");
        assert_eq!(from_atom_name("OW", "SOL", false).unwrap().0, "O");
        assert!(from_atom_name("123", "X", false).is_none());
        assert!(from_atom_name(" OM ", "TIP4", false).is_none(), "CHARMM's TIP4P site");
        assert_eq!(from_atom_name("OM", "LIG", false).unwrap().0, "O", "elsewhere an oxygen");
    }
}
