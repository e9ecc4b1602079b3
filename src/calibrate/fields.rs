//! How the user spelled the settings of a calibration: as the CLI's flags (`--max-particles`)
//! or as keyword arguments (`max_particles`, the Python package). The library checks the
//! settings once, for both, and its errors name the field the way the user wrote it.

/// The spelling of the user's fields in error messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Spelling {
    /// `--max-particles`
    Flags,
    /// `max_particles`
    Keywords,
}

impl Spelling {
    /// `field` (snake_case, as in the settings' types) as the user wrote it.
    pub fn name(self, field: &str) -> String {
        match self {
            Spelling::Flags => format!("--{}", field.replace('_', "-")),
            Spelling::Keywords => field.to_string(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_field_is_named_as_the_user_wrote_it() {
        assert_eq!(Spelling::Flags.name("max_particles"), "--max-particles");
        assert_eq!(Spelling::Keywords.name("max_particles"), "max_particles");
        assert_eq!(Spelling::Flags.name("data"), "--data");
    }
}
