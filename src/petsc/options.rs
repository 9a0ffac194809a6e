//! PETSc's options database.

use std::ffi::CString;

use petsc_ffi as p;

use super::chk;
use crate::error::Result;

/// True when `-name` is set (with any value).
pub fn has(name: &str) -> Result<bool> {
    let c = CString::new(name).expect("option names have no NUL");
    let mut set = p::PetscBool::PETSC_FALSE;
    chk!(PetscOptionsHasName(
        std::ptr::null_mut(),
        std::ptr::null(),
        c.as_ptr(),
        &mut set
    ))?;
    Ok(set == p::PetscBool::PETSC_TRUE)
}

/// Sets `-name value` unless the user already set `-name` (a default that options override).
pub fn set_default(name: &str, value: &str) -> Result<()> {
    if has(name)? {
        return Ok(());
    }
    let n = CString::new(name).expect("option names have no NUL");
    let v = CString::new(value).expect("option values have no NUL");
    chk!(PetscOptionsSetValue(
        std::ptr::null_mut(),
        n.as_ptr(),
        v.as_ptr()
    ))
}

/// Every option in the database as `(-name, value)`, in PETSc's order (`PetscOptionsGetAll`):
/// the command line, the options file, a study variant's and the defaults a run set.
pub fn all() -> Result<Vec<(String, Option<String>)>> {
    let mut text: *mut std::os::raw::c_char = std::ptr::null_mut();
    chk!(PetscOptionsGetAll(std::ptr::null_mut(), &mut text))?;
    if text.is_null() {
        return Ok(Vec::new());
    }
    // SAFETY: PETSc returned a NUL-terminated string it allocated for us; copied, then freed.
    let owned = unsafe { std::ffi::CStr::from_ptr(text) }
        .to_string_lossy()
        .into_owned();
    // SAFETY: `text` came from PetscMalloc inside PetscOptionsGetAll and is freed once.
    unsafe { p::petsc_ffi_free(text.cast()) };
    Ok(listed(&owned))
}

/// A word that names an option, as PETSc reads its command line: `-` and a letter (`-1` is a
/// value).
fn is_option_name(word: &str) -> bool {
    word.starts_with('-')
        && word[1..]
            .chars()
            .next()
            .is_some_and(|c| c.is_ascii_alphabetic())
}

/// The options of `PetscOptionsGetAll`'s string: a word starting with `-` and a letter is a
/// name, the words after it up to the next name its value (a value may hold spaces).
fn listed(text: &str) -> Vec<(String, Option<String>)> {
    let mut out: Vec<(String, Option<String>)> = Vec::new();
    for word in text.split_whitespace() {
        let is_name = is_option_name(word);
        match out.last_mut() {
            Some((_, value)) if !is_name => match value {
                Some(v) => {
                    v.push(' ');
                    v.push_str(word);
                }
                None => *value = Some(word.to_string()),
            },
            _ if is_name => out.push((word.to_string(), None)),
            // A stray word before any name: not an option.
            _ => {}
        }
    }
    out
}

/// The names of the options whose value is `value`: for an error message of PETSc that quotes
/// a bad value without saying whose it is ("Input string abc has no integer value").
pub fn named_by_value(value: &str) -> Vec<String> {
    all()
        .unwrap_or_default()
        .into_iter()
        .filter(|(_, v)| v.as_deref() == Some(value))
        .map(|(name, _)| name)
        .collect()
}

/// How many [`Override`]s with options of their own are alive: while one is, the options a
/// run reads include a study variant's (`petsc`), which messages then name as a source.
static OVERRIDES: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// True while a study variant's own PETSc options are in the database ([`Override`]).
pub fn overridden() -> bool {
    OVERRIDES.load(std::sync::atomic::Ordering::Relaxed) > 0
}

/// The options a run may write into the database as defaults ([`set_default`]: the linear
/// solver's, `ksp::set_linear_solver_defaults`, and the stash of a matrix on more than one rank,
/// `matrix::Matrix::new_aij`), restored with a study variant's own options ([`Override`]).
fn defaulted_options() -> impl Iterator<Item = &'static str> {
    super::ksp::defaulted_options().chain(["-matstash_legacy"])
}

/// Options set for a while (a study variant's runs): [`Override::set`] puts each `-name value`
/// into the database, over the options file and the command line, remembering what was there;
/// dropping the guard puts the old values back (or clears the names that were not set), each
/// with its mark of having been read, so that PETSc's count of unused options stays true. The
/// defaults a run writes into the database when the user chose none (the linear solver's,
/// `ksp::set_linear_solver_defaults`, and the stash of a matrix on more than one rank,
/// `matrix::Matrix::new_aij`; `defaulted_options`) are put back too, so that they follow
/// each run's own options and never leak from one run into the next.
#[derive(Debug)]
pub struct Override {
    /// Each name with what was there before.
    previous: Vec<(CString, Saved)>,
    /// The names set (not the defaults only saved).
    set: Vec<CString>,
    /// Counted in `OVERRIDES` (it has options of its own).
    counted: bool,
}

/// An option's value before an [`Override`], and whether something had read it.
#[derive(Debug)]
struct Saved {
    /// `None` = not set, `Some(None)` = set without a value.
    value: Option<Option<CString>>,
    used: bool,
}

impl Saved {
    fn of(name: &CString) -> Result<Saved> {
        // `used` first: reading the value marks it used.
        let used = is_used(name);
        Ok(Saved {
            value: current_value(name)?,
            used,
        })
    }
}

impl Override {
    /// Sets `options` (names with a leading `-` and their values, `None` for a flag).
    pub fn set(options: &[(String, Option<String>)]) -> Result<Override> {
        let mut guard = Override {
            previous: Vec::with_capacity(options.len()),
            set: Vec::with_capacity(options.len()),
            counted: !options.is_empty(),
        };
        if guard.counted {
            OVERRIDES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        }
        for name in defaulted_options() {
            let n = CString::new(name).expect("option names have no NUL");
            let saved = Saved::of(&n)?;
            guard.previous.push((n, saved));
        }
        for (name, value) in options {
            let n = CString::new(name.as_str()).expect("option names have no NUL");
            if !guard.previous.iter().any(|(saved, _)| *saved == n) {
                let saved = Saved::of(&n)?;
                guard.previous.push((n.clone(), saved));
            }
            guard.set.push(n.clone());
            let v = value
                .as_deref()
                .map(|v| CString::new(v).expect("option values have no NUL"));
            set_fresh(&n, v.as_ref())?;
        }
        Ok(guard)
    }

    /// The options set that no PETSc object read (typos, or options of a solver not in use).
    pub fn unused(&self) -> Vec<String> {
        self.set
            .iter()
            .filter(|n| !is_used(n))
            .map(|n| n.to_string_lossy().into_owned())
            .collect()
    }
}

impl Drop for Override {
    fn drop(&mut self) {
        if self.counted {
            OVERRIDES.fetch_sub(1, std::sync::atomic::Ordering::Relaxed);
        }
        for (name, before) in self.previous.drain(..).rev() {
            let restored = match &before.value {
                Some(value) => set_fresh(&name, value.as_ref()).and_then(|()| {
                    if before.used {
                        current_value(&name).map(drop)
                    } else {
                        Ok(())
                    }
                }),
                // SAFETY: a valid NUL-terminated name; the default database.
                None => chk!(PetscOptionsClearValue(std::ptr::null_mut(), name.as_ptr())),
            };
            if let Err(e) = restored {
                crate::error::print_warning(format_args!(
                    "could not restore PETSc option {}: {e}",
                    name.to_string_lossy()
                ));
            }
        }
    }
}

/// True when something read `-name` since it was set. The database keeps names without their
/// leading dash, and `PetscOptionsUsed` compares the name as given.
fn is_used(name: &CString) -> bool {
    let bare = name.to_bytes_with_nul();
    let bare = bare.strip_prefix(b"-").unwrap_or(bare);
    let mut used = p::PetscBool::PETSC_FALSE;
    // SAFETY: `bare` is a NUL-terminated name (a suffix of one); the default database.
    let code =
        unsafe { p::PetscOptionsUsed(std::ptr::null_mut(), bare.as_ptr().cast(), &mut used) };
    code == 0 && used == p::PetscBool::PETSC_TRUE
}

/// Sets `-name` as if it had never been set: PETSc keeps an entry's mark of having been read
/// when its value is replaced, so the entry is cleared first.
fn set_fresh(name: &CString, value: Option<&CString>) -> Result<()> {
    // SAFETY: a valid NUL-terminated name; the default database.
    chk!(PetscOptionsClearValue(std::ptr::null_mut(), name.as_ptr()))?;
    set_value(name, value)
}

/// The value of `-name` in the database: `None` if it is not set, `Some(None)` for a flag.
fn current_value(name: &CString) -> Result<Option<Option<CString>>> {
    let mut value: *const std::os::raw::c_char = std::ptr::null();
    let mut set = p::PetscBool::PETSC_FALSE;
    chk!(PetscOptionsFindPair(
        std::ptr::null_mut(),
        std::ptr::null(),
        name.as_ptr(),
        &mut value,
        &mut set
    ))?;
    if set != p::PetscBool::PETSC_TRUE {
        return Ok(None);
    }
    if value.is_null() {
        return Ok(Some(None));
    }
    // SAFETY: PETSc returned a NUL-terminated string it owns; it is copied at once.
    let owned = unsafe { std::ffi::CStr::from_ptr(value) }.to_owned();
    Ok(Some(Some(owned)))
}

fn set_value(name: &CString, value: Option<&CString>) -> Result<()> {
    chk!(PetscOptionsSetValue(
        std::ptr::null_mut(),
        name.as_ptr(),
        value.map_or(std::ptr::null(), |v| v.as_ptr())
    ))
}

/// Splits an options string (`-ksp_type gmres -pc_type gamg -ksp_monitor`) into names and
/// values, as PETSc reads its command line: a word starting with `-` and a letter is a name,
/// any other word is the value of the name before it. An error names the first stray value.
pub fn parse(text: &str) -> std::result::Result<Vec<(String, Option<String>)>, String> {
    if text.contains('\0') {
        return Err("contains a NUL character".into());
    }
    parse_words(text.split_whitespace())
}

/// [`parse`] of words already split (a command line's arguments).
pub fn parse_words<'a>(
    words: impl IntoIterator<Item = &'a str>,
) -> std::result::Result<Vec<(String, Option<String>)>, String> {
    let mut out: Vec<(String, Option<String>)> = Vec::new();
    for word in words {
        let is_name = is_option_name(word);
        if is_name {
            out.push((word.to_string(), None));
        } else {
            match out.last_mut() {
                Some((_, value @ None)) => *value = Some(word.to_string()),
                Some((name, Some(_))) => {
                    return Err(format!(
                        "'{word}' follows {name} and its value: not an option"
                    ))
                }
                None => return Err(format!("'{word}' is not an option (options start with -)")),
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::{listed, parse};

    #[test]
    fn the_database_listing_keeps_values_with_spaces() {
        let got = listed("-ksp_type gmres -title my run -x -1 -flag");
        let want: Vec<(String, Option<String>)> = vec![
            ("-ksp_type".into(), Some("gmres".into())),
            ("-title".into(), Some("my run".into())),
            ("-x".into(), Some("-1".into())),
            ("-flag".into(), None),
        ];
        assert_eq!(got, want);
        assert!(listed("").is_empty());
    }

    #[test]
    fn options_strings_split_into_names_and_values() {
        let p = parse(" -ksp_type gmres  -ksp_monitor -ksp_rtol 1e-8 -x -1").unwrap();
        let want: Vec<(String, Option<String>)> = vec![
            ("-ksp_type".into(), Some("gmres".into())),
            ("-ksp_monitor".into(), None),
            ("-ksp_rtol".into(), Some("1e-8".into())),
            ("-x".into(), Some("-1".into())),
        ];
        assert_eq!(p, want);
        assert!(parse("gmres").unwrap_err().contains("gmres"));
        assert!(parse("-a b c").unwrap_err().contains("'c'"));
        assert!(parse("").unwrap().is_empty());
    }
}
