//! The access token of the browser control surface: a random secret the page's URL carries, so
//! a stranger on the venue's network who finds the port can watch the values (as any OSCQuery
//! client can) but not take the show over.

use super::super::http::Request;

/// Name of the cookie that carries the token after the page was opened with it, so WebSocket
/// handshakes from the page (and from other OSCQuery pages served here) carry it too.
pub const COOKIE: &str = "indra_token";
/// Shortest token accepted from the command line.
pub const MIN_LEN: usize = 12;
/// Longest token accepted from the command line.
pub const MAX_LEN: usize = 128;

/// A secret that grants control.
#[derive(Clone, PartialEq, Eq)]
pub struct AccessToken(String);

impl std::fmt::Debug for AccessToken {
    /// Never printed by accident: logs and panics show its length only.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "AccessToken({} chars)", self.0.len())
    }
}

impl AccessToken {
    /// 128 random bits from the operating system, as 32 hex digits.
    pub fn random() -> Result<Self, String> {
        let mut bytes = [0u8; 16];
        getrandom::fill(&mut bytes).map_err(|e| format!("no random numbers for the access token: {e}"))?;
        Ok(Self(bytes.iter().map(|b| format!("{b:02x}")).collect()))
    }

    /// A token chosen by the performer (`--web-token`): [`MIN_LEN`] to [`MAX_LEN`] characters
    /// of `A–Z a–z 0–9 - _`, so it needs no escaping in a URL or a cookie.
    pub fn chosen(token: &str) -> Result<Self, String> {
        let allowed = token.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'_');
        if !allowed || !(MIN_LEN..=MAX_LEN).contains(&token.len()) {
            return Err(format!(
                "an access token is {MIN_LEN} to {MAX_LEN} characters of A-Z a-z 0-9 - _ (got {} characters)",
                token.len()
            ));
        }
        Ok(Self(token.to_string()))
    }

    /// The token, for the URL printed to the performer.
    pub fn as_str(&self) -> &str {
        &self.0
    }

    /// Whether `request` carries this token, in its query (`?token=…`) or its cookie.
    pub fn admits(&self, request: &Request<'_>) -> bool {
        [request.query_param("token"), request.cookie(COOKIE)].into_iter().flatten().any(|t| self.matches(t))
    }

    /// Whether `request` names this token in its URL (`?token=…`), its cookie aside.
    pub fn admits_in_url(&self, request: &Request<'_>) -> bool {
        request.query_param("token").is_some_and(|t| self.matches(t))
    }

    /// Compares in time independent of where the strings differ, so response times do not
    /// give the token away a character at a time.
    fn matches(&self, offered: &str) -> bool {
        let (want, got) = (self.0.as_bytes(), offered.as_bytes());
        want.len() == got.len() && want.iter().zip(got).fold(0u8, |diff, (a, b)| diff | (a ^ b)) == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn random_tokens_differ_and_only_the_exact_token_admits() {
        let token = AccessToken::random().unwrap();
        assert_eq!(token.as_str().len(), 32);
        assert_ne!(token, AccessToken::random().unwrap());
        let with = |headers: &str, target: &str| token.admits(&Request::new(target, headers));
        assert!(with("", &format!("/?token={}", token.as_str())));
        assert!(with(&format!("Cookie: x=1; {COOKIE}={}", token.as_str()), "/"));
        assert!(!with("", "/"));
        assert!(!with("", &format!("/?token={}", &token.as_str()[..31])), "a prefix");
        assert!(!with("", &format!("/?token={}0", token.as_str())), "a longer one");
        assert!(!with("", "/?token="));
        assert!(!format!("{token:?}").contains(token.as_str()), "Debug leaks the token");
    }

    #[test]
    fn a_chosen_token_is_url_safe_and_long_enough() {
        assert!(AccessToken::chosen("stage-left_2026").is_ok());
        assert!(AccessToken::chosen("short").is_err());
        assert!(AccessToken::chosen("has a space in it").is_err());
        assert!(AccessToken::chosen("semi;colon;cookie").is_err());
        assert!(AccessToken::chosen(&"x".repeat(MAX_LEN + 1)).is_err());
    }
}
