//! Who may operate: with a token configured, a Foxglove client operates only after it
//! gave the token (the `auth` service, as a TCP client of the control socket sends
//! `auth`); without one (loopback only, the daemon checks), every client may.

use std::collections::{HashMap, HashSet};
use std::sync::{Mutex, MutexGuard, PoisonError};
use std::time::Duration;

/// A wrong token is answered after this long.
pub const FAILURE_DELAY: Duration = Duration::from_secs(1);
/// Wrong tokens a client may send; after that it is refused until it reconnects.
pub const MAX_FAILURES: u32 = 3;

/// The clients that gave the token.
#[derive(Debug, Default)]
pub struct Access {
    token: Option<String>,
    authorised: Mutex<HashSet<u32>>,
    failures: Mutex<HashMap<u32, u32>>,
}

impl Access {
    pub fn new(token: Option<String>) -> Self {
        Self {
            token: token.filter(|t| !t.is_empty()),
            authorised: Mutex::default(),
            failures: Mutex::default(),
        }
    }

    fn set(&self) -> MutexGuard<'_, HashSet<u32>> {
        // A panic while inserting leaves the set as it was or with the id: still sound.
        self.authorised
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
    }

    /// Whether clients must give a token.
    pub fn required(&self) -> bool {
        self.token.is_some()
    }

    pub fn may_operate(&self, client: u32) -> bool {
        self.token.is_none() || self.set().contains(&client)
    }

    /// Checks `token` (in constant time) and remembers the client if it is right;
    /// refused, saying why: a wrong token, or too many of them from this client.
    pub fn authenticate(&self, client: u32, token: &str) -> Result<(), &'static str> {
        use subtle::ConstantTimeEq;
        let mut failures = self.failures.lock().unwrap_or_else(PoisonError::into_inner);
        let failed = failures.entry(client).or_default();
        if *failed >= MAX_FAILURES {
            return Err("too many wrong tokens from this client: reconnect");
        }
        let ok = match &self.token {
            None => true,
            Some(t) => bool::from(t.as_bytes().ct_eq(token.as_bytes())),
        };
        if !ok {
            *failed += 1;
            return Err("wrong token");
        }
        failures.remove(&client);
        drop(failures);
        self.set().insert(client);
        Ok(())
    }

    /// The client went away (its id is never reused, so this only frees memory).
    pub fn forget(&self, client: u32) {
        self.set().remove(&client);
        let mut failures = self.failures.lock().unwrap_or_else(PoisonError::into_inner);
        failures.remove(&client);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_token_is_required_of_each_client_once() {
        let a = Access::new(Some("s3cret".into()));
        assert!(a.required());
        assert!(!a.may_operate(1));
        assert!(a.authenticate(1, "wrong").is_err());
        assert!(!a.may_operate(1));
        assert!(a.authenticate(1, "s3cret").is_ok());
        assert!(a.may_operate(1) && !a.may_operate(2), "per client");
        a.forget(1);
        assert!(!a.may_operate(1));
    }

    #[test]
    fn a_client_gets_a_few_tries_only() {
        let a = Access::new(Some("s3cret".into()));
        for _ in 0..MAX_FAILURES {
            assert_eq!(a.authenticate(1, "guess"), Err("wrong token"));
        }
        let refused = a.authenticate(1, "s3cret").unwrap_err();
        assert!(refused.contains("too many"), "{refused}");
        assert!(!a.may_operate(1));
        assert!(a.authenticate(2, "s3cret").is_ok(), "per client");
    }

    #[test]
    fn without_a_token_everyone_may() {
        for a in [Access::new(None), Access::new(Some(String::new()))] {
            assert!(!a.required());
            assert!(a.may_operate(7));
        }
    }
}
