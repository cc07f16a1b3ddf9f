//! Writing a model blob from a trained model's tables (the host's side of the format).

use super::*;

/// The tables of a trained model, in z-space, for [`write_model`]. Lengths: p for
/// `feature_index`, `mean`, `scale`; C for `positions_mm`, `log_prior`, `constant`; C x p for
/// `vectors` (mu_c for QDA, w_c for LDA, class-major); C x p(p+1)/2 for `factors` (QDA only,
/// packed lower triangle by rows; empty for LDA).
#[derive(Debug, Clone, Copy)]
pub struct ModelTables<'t> {
    /// QDA or LDA.
    pub kind: ModelKind,
    /// Storage precision of `vectors` and `factors`.
    pub precision: Precision,
    /// Trained on V_m - V_0 ([`FLAG_REFERENCED`]).
    pub referenced: bool,
    /// Electrode count L of the frames.
    pub electrodes: u8,
    /// Protocol of the frames.
    pub protocol: ProtocolKind,
    /// Frame index of each feature.
    pub feature_index: &'t [u16],
    /// Feature means (volts).
    pub mean: &'t [f32],
    /// Feature scales (volts, > 0).
    pub scale: &'t [f32],
    /// Class centres on the sheet (mm).
    pub positions_mm: &'t [[f32; 2]],
    /// log pi_c.
    pub log_prior: &'t [f32],
    /// QDA: -1/2 log|Sigma_c|; LDA: -1/2 mu_c^T Sigma^-1 mu_c.
    pub constant: &'t [f32],
    /// QDA: mu_c; LDA: w_c = Sigma^-1 mu_c.
    pub vectors: &'t [f32],
    /// QDA: L_c with Sigma_c = L_c L_c^T.
    pub factors: &'t [f32],
}

/// Writes a model blob into `out` and returns its length; the result is checked with
/// [`Model::parse`] before returning, so a blob that is written is a blob that loads.
///
/// # Errors
/// [`ModelError::Table`] for inconsistent lengths or a short `out`, else what
/// [`Model::parse`] finds.
// Writes our own tables into `out[..len]`, whose length is checked first; nothing read here
// comes from a file or the wire, and the result is re-read by `Model::parse`.
#[allow(clippy::indexing_slicing)]
pub fn write_model(t: &ModelTables<'_>, out: &mut [u8]) -> Result<usize, ModelError> {
    let p = t.feature_index.len();
    let c_n = t.positions_mm.len();
    let protocol = Protocol::new(t.protocol, t.electrodes).map_err(ModelError::Protocol)?;
    let factors_len = match t.kind {
        ModelKind::Qda => c_n * packed_len(p),
        ModelKind::Lda => 0,
    };
    if t.mean.len() != p
        || t.scale.len() != p
        || t.log_prior.len() != c_n
        || t.constant.len() != c_n
        || t.vectors.len() != c_n * p
        || t.factors.len() != factors_len
        || p > usize::from(u16::MAX)
        || c_n > usize::from(u16::MAX)
    {
        return Err(ModelError::Table);
    }
    let lay = layout(t.kind, t.precision, c_n, p).ok_or(ModelError::Table)?;
    let len = lay.crc + 4;
    let out = out.get_mut(..len).ok_or(ModelError::Table)?;
    out.fill(0);
    out[..4].copy_from_slice(&MODEL_MAGIC);
    out[4..6].copy_from_slice(&MODEL_VERSION.to_le_bytes());
    out[6] = match t.kind {
        ModelKind::Qda => 0,
        ModelKind::Lda => 1,
    };
    out[7] = match t.precision {
        Precision::F32 => 0,
        Precision::F16 => 1,
    };
    out[8..10].copy_from_slice(&(c_n as u16).to_le_bytes());
    out[10..12].copy_from_slice(&(p as u16).to_le_bytes());
    out[12..14].copy_from_slice(&(protocol.frame_len() as u16).to_le_bytes());
    out[14] = t.electrodes;
    out[17] = if t.referenced { FLAG_REFERENCED } else { 0 };
    let (tag, pattern) = protocol_tag(t.protocol);
    out[15] = tag;
    out[16] = pattern.drive_skip;
    out[18..22].copy_from_slice(&pattern.measure_skips.0.to_le_bytes());
    let put_f32 = |out: &mut [u8], at: usize, v: &[f32]| {
        for (i, x) in v.iter().enumerate() {
            out[at + 4 * i..at + 4 * i + 4].copy_from_slice(&x.to_le_bytes());
        }
    };
    let put_stored = |out: &mut [u8], at: usize, v: &[f32]| match t.precision {
        Precision::F32 => put_f32(out, at, v),
        Precision::F16 => {
            for (i, x) in v.iter().enumerate() {
                out[at + 2 * i..at + 2 * i + 2].copy_from_slice(&f32_to_f16(*x).to_le_bytes());
            }
        }
    };
    for (j, idx) in t.feature_index.iter().enumerate() {
        out[lay.feature_index + 2 * j..lay.feature_index + 2 * j + 2]
            .copy_from_slice(&idx.to_le_bytes());
    }
    put_f32(out, lay.mean, t.mean);
    put_f32(out, lay.scale, t.scale);
    for (c, [x, y]) in t.positions_mm.iter().enumerate() {
        put_f32(out, lay.positions + 8 * c, &[*x, *y]);
    }
    put_f32(out, lay.log_prior, t.log_prior);
    put_f32(out, lay.constant, t.constant);
    put_stored(out, lay.vectors, t.vectors);
    put_stored(out, lay.factors, t.factors);
    let crc = crc32(&out[..lay.crc]);
    out[lay.crc..].copy_from_slice(&crc.to_le_bytes());
    Model::parse(out)?;
    Ok(len)
}
