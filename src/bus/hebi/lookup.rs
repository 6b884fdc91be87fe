//! Finding modules with libhebi's lookup and making the group: by names in body order,
//! a whole family with an order map, or an imitation group (no network). A lookup sends
//! to the configured interfaces only; with none, libhebi broadcasts on every interface
//! except loopback.

use std::ffi::{CString, c_char};
use std::time::{Duration, Instant};

use super::ffi::{EntryListPtr, GroupPtr, LookupPtr, MacAddress, STATUS_SUCCESS};
use super::library::Api;

/// Which modules make the group.
#[derive(Debug, Clone, PartialEq)]
pub enum Source {
    /// HEBI's imitation group of this many modules: echoes commands as feedback.
    Imitation(usize),
    /// These names of `family`, head first.
    Names { family: String, names: Vec<String> },
    /// Every module of `family` the lookup finds, `expected` of them, in the
    /// lookup's order as mapped by the order map.
    Family { family: String, expected: usize },
}

#[derive(Debug, Clone, PartialEq)]
pub struct Spec {
    pub interfaces: Vec<String>,
    pub source: Source,
    /// Body position `i` is the group's module `order[i]`; empty = the group's order.
    pub order: Vec<usize>,
    pub timeout: Duration,
}

pub struct Opened {
    pub group: GroupPtr,
    pub lookup: LookupPtr,
    /// Module names, head first.
    pub names: Vec<String>,
    pub order: Vec<usize>,
    pub imitation: bool,
}

/// A module a lookup found.
#[derive(Debug, Clone, PartialEq)]
pub struct Found {
    pub family: String,
    pub name: String,
    pub mac: [u8; 6],
}

impl std::fmt::Display for Found {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let m = self.mac;
        write!(
            f,
            "{:<12} {:<16} {:02x}:{:02x}:{:02x}:{:02x}:{:02x}:{:02x}",
            self.family, self.name, m[0], m[1], m[2], m[3], m[4], m[5]
        )
    }
}

fn where_(interfaces: &[String]) -> String {
    if interfaces.is_empty() {
        "every interface but loopback".into()
    } else {
        interfaces.join(", ")
    }
}

fn create_lookup(api: &Api, interfaces: &[String]) -> Result<LookupPtr, String> {
    let c: Vec<CString> = interfaces
        .iter()
        .map(|i| CString::new(i.as_str()).map_err(|_| format!("interface {i:?}: contains NUL")))
        .collect::<Result<_, _>>()?;
    let ptrs: Vec<*const c_char> = c.iter().map(|s| s.as_ptr()).collect();
    let (p, n) = if ptrs.is_empty() {
        (std::ptr::null(), 0)
    } else {
        (ptrs.as_ptr(), ptrs.len())
    };
    // SAFETY: n valid NUL-terminated strings (or null, 0); the library copies them.
    let lookup = unsafe { (api.f.lookup_create)(p, n) };
    if lookup.is_null() {
        return Err(format!(
            "libhebi could not start a lookup on {}: {}",
            where_(interfaces),
            api.last_error()
        ));
    }
    Ok(lookup)
}

fn entry_string(
    api: &Api,
    list: EntryListPtr,
    i: usize,
    get: unsafe extern "C" fn(EntryListPtr, usize, *mut c_char, *mut usize) -> i32,
) -> String {
    let mut buf = [0 as c_char; 64];
    let mut len = buf.len();
    // SAFETY: a buffer of `len` bytes; the library writes a NUL-terminated string.
    if unsafe { get(list, i, buf.as_mut_ptr(), &mut len) } != STATUS_SUCCESS {
        return "?".into();
    }
    let _ = api;
    // SAFETY: NUL-terminated within the buffer on success.
    unsafe { std::ffi::CStr::from_ptr(buf.as_ptr()) }
        .to_string_lossy()
        .into_owned()
}

fn entries(api: &Api, lookup: LookupPtr) -> Vec<Found> {
    // SAFETY: a live lookup; the list is released below.
    let list = unsafe { (api.f.create_lookup_entry_list)(lookup) };
    if list.is_null() {
        return vec![];
    }
    let n = unsafe { (api.f.lookup_entry_list_get_size)(list) };
    let out = (0..n)
        .map(|i| {
            let mut mac = MacAddress::default();
            // SAFETY: i < n; a valid out-pointer.
            unsafe { (api.f.lookup_entry_list_get_mac_address)(list, i, &mut mac) };
            Found {
                family: entry_string(api, list, i, api.f.lookup_entry_list_get_family),
                name: entry_string(api, list, i, api.f.lookup_entry_list_get_name),
                mac: mac.bytes,
            }
        })
        .collect();
    unsafe { (api.f.lookup_entry_list_release)(list) };
    out
}

/// What a lookup on `interfaces` finds in `wait` (`snaked --list-modules`).
pub fn list(api: &Api, interfaces: &[String], wait: Duration) -> Result<Vec<Found>, String> {
    let lookup = create_lookup(api, interfaces)?;
    std::thread::sleep(wait);
    let found = entries(api, lookup);
    // SAFETY: live, released once.
    unsafe { (api.f.lookup_release)(lookup) };
    Ok(found)
}

/// Checks an order map against a group of `n`: a permutation of 0..n, or empty.
pub fn order_for(order: &[usize], n: usize) -> Result<Vec<usize>, String> {
    if order.is_empty() {
        return Ok((0..n).collect());
    }
    let mut seen = vec![false; n];
    if order.len() != n {
        return Err(format!(
            "hebi.order has {} entries for {n} modules",
            order.len()
        ));
    }
    for &g in order {
        if g >= n || std::mem::replace(&mut seen[g], true) {
            return Err(format!(
                "hebi.order must list each of 0..{} once (found {g} out of range or twice)",
                n - 1
            ));
        }
    }
    Ok(order.to_vec())
}

/// Makes the group `spec` asks for. A module that does not answer in time refuses the
/// start, naming it and what the lookup did find.
pub fn open(api: &Api, spec: &Spec) -> Result<Opened, String> {
    let timeout_ms = spec.timeout.as_millis().min(i32::MAX as u128) as i32;
    match &spec.source {
        Source::Imitation(n) => {
            // SAFETY: plain constructor.
            let group = unsafe { (api.f.group_create_imitation)(*n) };
            if group.is_null() {
                return Err(format!(
                    "libhebi made no imitation group: {}",
                    api.last_error()
                ));
            }
            let names = (0..*n).map(|g| format!("imitation{g}")).collect();
            finish(api, group, std::ptr::null_mut(), names, &spec.order, true)
        }
        Source::Names { family, names } => {
            let lookup = create_lookup(api, &spec.interfaces)?;
            let fam = CString::new(family.as_str()).map_err(|_| "hebi.family contains NUL")?;
            let c_names: Vec<CString> = names
                .iter()
                .map(|n| CString::new(n.as_str()).map_err(|_| format!("name {n:?} contains NUL")))
                .collect::<Result<_, _>>()?;
            let fams = [fam.as_ptr()];
            let ptrs: Vec<*const c_char> = c_names.iter().map(|s| s.as_ptr()).collect();
            let start = Instant::now();
            // SAFETY: valid string arrays; blocks up to the timeout (start-up only).
            let group = unsafe {
                (api.f.group_create_from_names)(
                    lookup,
                    fams.as_ptr(),
                    1,
                    ptrs.as_ptr(),
                    ptrs.len(),
                    timeout_ms,
                )
            };
            if group.is_null() {
                let found = entries(api, lookup);
                unsafe { (api.f.lookup_release)(lookup) };
                let missing: Vec<&str> = names
                    .iter()
                    .filter(|n| !found.iter().any(|f| &f.family == family && &f.name == *n))
                    .map(String::as_str)
                    .collect();
                return Err(not_found(
                    &format!("module(s) {} of family {family}", missing.join(", ")),
                    spec,
                    start.elapsed(),
                    &found,
                ));
            }
            finish(api, group, lookup, names.clone(), &spec.order, false)
        }
        Source::Family { family, expected } => {
            let lookup = create_lookup(api, &spec.interfaces)?;
            let fam = CString::new(family.as_str()).map_err(|_| "hebi.family contains NUL")?;
            let start = Instant::now();
            // SAFETY: a valid string; blocks up to the timeout (start-up only).
            let group =
                unsafe { (api.f.group_create_from_family)(lookup, fam.as_ptr(), timeout_ms) };
            let found = entries(api, lookup);
            let of_family: Vec<&Found> = found.iter().filter(|f| &f.family == family).collect();
            let size = if group.is_null() {
                0
            } else {
                unsafe { (api.f.group_get_size)(group) }
            };
            if size != *expected {
                unsafe {
                    if !group.is_null() {
                        (api.f.group_release)(group);
                    }
                    (api.f.lookup_release)(lookup);
                }
                return Err(not_found(
                    &format!("{expected} modules of family {family} (the group has {size})"),
                    spec,
                    start.elapsed(),
                    &found,
                ));
            }
            // The group takes the family in the lookup's order.
            let names = (0..size)
                .map(|g| {
                    of_family
                        .get(g)
                        .map_or(format!("{family}{g}"), |f| f.name.clone())
                })
                .collect();
            finish(api, group, lookup, names, &spec.order, false)
        }
    }
}

/// The group with its names (group order) put in body order by `order`; released when
/// the order does not fit.
fn finish(
    api: &Api,
    group: GroupPtr,
    lookup: LookupPtr,
    names: Vec<String>,
    order: &[usize],
    imitation: bool,
) -> Result<Opened, String> {
    let order = order_for(order, names.len()).inspect_err(|_| {
        // SAFETY: live handles we own, released once.
        unsafe {
            (api.f.group_release)(group);
            if !lookup.is_null() {
                (api.f.lookup_release)(lookup);
            }
        }
    })?;
    Ok(Opened {
        group,
        lookup,
        names: order.iter().map(|&g| names[g].clone()).collect(),
        order,
        imitation,
    })
}

fn not_found(what: &str, spec: &Spec, waited: Duration, found: &[Found]) -> String {
    let seen = if found.is_empty() {
        "nothing answered".to_owned()
    } else {
        let all: Vec<String> = found
            .iter()
            .map(|f| format!("{}/{}", f.family, f.name))
            .collect();
        format!("found {}", all.join(", "))
    };
    format!(
        "{what} not found on {} in {:.1} s; {seen} (snaked --list-modules shows what answers)",
        where_(&spec.interfaces),
        waited.as_secs_f64()
    )
}
