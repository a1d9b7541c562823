//! TLS for IEC 104 in the IEC 62351-3 profile: TLS 1.2 or 1.3 only, mutual
//! authentication with X.509 certificates on both sides, peers checked against the
//! configured trust anchors.
//!
//! rustls offers no renegotiation and no weak suites, which IEC 62351-3 asks to avoid
//! anyway; session resumption stays on (rustls' default) as the profile allows it.

use std::io::BufReader;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use tokio_rustls::rustls;
use tokio_rustls::rustls::pki_types::{CertificateDer, PrivateKeyDer};
use tokio_rustls::rustls::server::WebPkiClientVerifier;
use tokio_rustls::rustls::RootCertStore;

/// Why a TLS configuration could not be built.
#[derive(Debug, thiserror::Error)]
pub enum TlsError {
    /// A file could not be read.
    #[error("cannot read {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A file could not be written.
    #[error("cannot write {path}: {source}")]
    Write {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A PEM file holds nothing usable.
    #[error("{what} not found in {path}")]
    Missing {
        /// What was looked for.
        what: &'static str,
        /// The file.
        path: PathBuf,
    },
    /// rustls refused the material.
    #[error("TLS configuration refused: {0}")]
    Rustls(#[from] rustls::Error),
    /// The trust anchors are unusable.
    #[error("client verifier: {0}")]
    Verifier(String),
}

/// The PEM files of one end of a link.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TlsFiles {
    /// This station's certificate chain (leaf first).
    pub certificate: PathBuf,
    /// This station's private key.
    pub private_key: PathBuf,
    /// Certificates of the authorities that sign the peers' certificates.
    pub trust_anchors: PathBuf,
}

/// PEM material already in memory.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TlsPem {
    /// This station's certificate chain.
    pub certificate: Vec<u8>,
    /// This station's private key.
    pub private_key: Vec<u8>,
    /// The peers' certificate authorities.
    pub trust_anchors: Vec<u8>,
}

impl TlsFiles {
    /// Reads the three files.
    pub fn load(&self) -> Result<TlsPem, TlsError> {
        let read = |path: &Path| {
            std::fs::read(path).map_err(|source| TlsError::Read {
                path: path.to_owned(),
                source,
            })
        };
        Ok(TlsPem {
            certificate: read(&self.certificate)?,
            private_key: read(&self.private_key)?,
            trust_anchors: read(&self.trust_anchors)?,
        })
    }
}

fn provider() -> Arc<rustls::crypto::CryptoProvider> {
    Arc::new(rustls::crypto::ring::default_provider())
}

fn certificates(pem: &[u8], what: &'static str) -> Result<Vec<CertificateDer<'static>>, TlsError> {
    let certificates: Vec<_> = rustls_pemfile::certs(&mut BufReader::new(pem))
        .filter_map(Result::ok)
        .collect();
    if certificates.is_empty() {
        return Err(TlsError::Missing {
            what,
            path: PathBuf::from("<pem>"),
        });
    }
    Ok(certificates)
}

fn private_key(pem: &[u8]) -> Result<PrivateKeyDer<'static>, TlsError> {
    rustls_pemfile::private_key(&mut BufReader::new(pem))
        .ok()
        .flatten()
        .ok_or(TlsError::Missing {
            what: "private key",
            path: PathBuf::from("<pem>"),
        })
}

fn roots(pem: &[u8]) -> Result<RootCertStore, TlsError> {
    let mut store = RootCertStore::empty();
    for certificate in certificates(pem, "trust anchor certificate")? {
        store.add(certificate)?;
    }
    Ok(store)
}

/// A server configuration that requires and verifies client certificates.
pub fn server_config(pem: &TlsPem) -> Result<Arc<rustls::ServerConfig>, TlsError> {
    let provider = provider();
    let verifier = WebPkiClientVerifier::builder_with_provider(
        Arc::new(roots(&pem.trust_anchors)?),
        Arc::clone(&provider),
    )
    .build()
    .map_err(|error| TlsError::Verifier(error.to_string()))?;
    let config = rustls::ServerConfig::builder_with_provider(provider)
        .with_protocol_versions(&[&rustls::version::TLS13, &rustls::version::TLS12])?
        .with_client_cert_verifier(verifier)
        .with_single_cert(
            certificates(&pem.certificate, "certificate")?,
            private_key(&pem.private_key)?,
        )?;
    Ok(Arc::new(config))
}

/// What a client needs for TLS: its configuration and the name the server's certificate
/// must carry.
pub type ClientTls = (
    Arc<rustls::ClientConfig>,
    tokio_rustls::rustls::pki_types::ServerName<'static>,
);

/// A client configuration that presents its certificate and verifies the server's.
pub fn client_config(pem: &TlsPem) -> Result<Arc<rustls::ClientConfig>, TlsError> {
    let config = rustls::ClientConfig::builder_with_provider(provider())
        .with_protocol_versions(&[&rustls::version::TLS13, &rustls::version::TLS12])?
        .with_root_certificates(roots(&pem.trust_anchors)?)
        .with_client_auth_cert(
            certificates(&pem.certificate, "certificate")?,
            private_key(&pem.private_key)?,
        )?;
    Ok(Arc::new(config))
}

/// The name a client expects in the server's certificate: a DNS name or an IP address.
pub fn server_name(
    host: &str,
) -> Result<tokio_rustls::rustls::pki_types::ServerName<'static>, TlsError> {
    tokio_rustls::rustls::pki_types::ServerName::try_from(host.to_owned()).map_err(|error| {
        TlsError::Verifier(format!("'{host}' is not a valid server name: {error}"))
    })
}

/// A throwaway certificate authority, for a demo or a test: a self-signed CA that issues
/// certificates for hosts. Never for production: the keys live in memory and in whatever
/// files the caller writes.
#[cfg(feature = "self-signed")]
pub mod self_signed {
    use std::path::Path;

    use rcgen::{
        BasicConstraints, CertificateParams, DnType, ExtendedKeyUsagePurpose, IsCa, Issuer,
        KeyPair, KeyUsagePurpose,
    };

    use super::{TlsError, TlsFiles, TlsPem};

    /// What a certificate may be used for.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum Usage {
        /// A server's certificate.
        Server,
        /// A client's certificate.
        Client,
        /// Both: a station that serves the nodes above it and is a client of those below.
        ServerAndClient,
    }

    /// A self-signed certificate authority.
    pub struct Authority {
        pem: String,
        issuer: Issuer<'static, KeyPair>,
    }

    impl std::fmt::Debug for Authority {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.debug_struct("Authority").finish_non_exhaustive()
        }
    }

    fn failed(error: rcgen::Error) -> TlsError {
        TlsError::Verifier(format!("cannot make a certificate: {error}"))
    }

    impl Authority {
        /// A new authority with a fresh key.
        pub fn new(name: &str) -> Result<Authority, TlsError> {
            let mut params = CertificateParams::new(Vec::<String>::new()).map_err(failed)?;
            params.distinguished_name.push(DnType::CommonName, name);
            params.is_ca = IsCa::Ca(BasicConstraints::Unconstrained);
            params.key_usages = vec![
                KeyUsagePurpose::KeyCertSign,
                KeyUsagePurpose::CrlSign,
                KeyUsagePurpose::DigitalSignature,
            ];
            let key = KeyPair::generate().map_err(failed)?;
            let certificate = params.self_signed(&key).map_err(failed)?;
            Ok(Authority {
                pem: certificate.pem(),
                issuer: Issuer::new(params, key),
            })
        }

        /// The authority's certificate (what peers trust), PEM encoded.
        pub fn certificate_pem(&self) -> &str {
            &self.pem
        }

        /// A certificate for `names` (DNS names or IP addresses; the first is also the
        /// common name) with its key, and this authority as the trust anchor.
        pub fn issue(&self, names: &[&str], usage: Usage) -> Result<TlsPem, TlsError> {
            let names: Vec<String> = names.iter().map(|name| (*name).to_owned()).collect();
            let mut params = CertificateParams::new(names.clone()).map_err(failed)?;
            if let Some(first) = names.first() {
                params
                    .distinguished_name
                    .push(DnType::CommonName, first.clone());
            }
            params.extended_key_usages = match usage {
                Usage::Server => vec![ExtendedKeyUsagePurpose::ServerAuth],
                Usage::Client => vec![ExtendedKeyUsagePurpose::ClientAuth],
                Usage::ServerAndClient => vec![
                    ExtendedKeyUsagePurpose::ServerAuth,
                    ExtendedKeyUsagePurpose::ClientAuth,
                ],
            };
            params.use_authority_key_identifier_extension = true;
            let key = KeyPair::generate().map_err(failed)?;
            let certificate = params.signed_by(&key, &self.issuer).map_err(failed)?;
            Ok(TlsPem {
                certificate: certificate.pem().into_bytes(),
                private_key: key.serialize_pem().into_bytes(),
                trust_anchors: self.pem.clone().into_bytes(),
            })
        }
    }

    /// Writes PEM material as `STEM.pem`, `STEM.key` and `STEM-ca.pem` in `folder` (the
    /// key readable by the owner only) and returns their paths.
    pub fn write(pem: &TlsPem, folder: &Path, stem: &str) -> Result<TlsFiles, TlsError> {
        let files = TlsFiles {
            certificate: folder.join(format!("{stem}.pem")),
            private_key: folder.join(format!("{stem}.key")),
            trust_anchors: folder.join(format!("{stem}-ca.pem")),
        };
        let write = |path: &Path, bytes: &[u8]| {
            std::fs::write(path, bytes).map_err(|source| TlsError::Write {
                path: path.to_owned(),
                source,
            })
        };
        write(&files.certificate, &pem.certificate)?;
        write(&files.private_key, &pem.private_key)?;
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let _ = std::fs::set_permissions(
                &files.private_key,
                std::fs::Permissions::from_mode(0o600),
            );
        }
        write(&files.trust_anchors, &pem.trust_anchors)?;
        Ok(files)
    }
}
