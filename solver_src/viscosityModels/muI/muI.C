/*---------------------------------------------------------------------------*\
  foamsilo: granular silo discharge with OpenFOAM
-------------------------------------------------------------------------------
License
    This file is part of foamsilo, built against OpenFOAM (GPL-3.0-or-later).
    It is distributed under the GNU General Public License v3 or later.

\*---------------------------------------------------------------------------*/

#include "muI.H"
#include "addToRunTimeSelectionTable.H"
#include "surfaceFields.H"

// * * * * * * * * * * * * * * Static Data Members * * * * * * * * * * * * * //

namespace Foam
{
namespace viscosityModels
{
    defineTypeNameAndDebug(muI, 0);

    addToRunTimeSelectionTable
    (
        viscosityModel,
        muI,
        dictionary
    );
}
}


// * * * * * * * * * * * * Private Member Functions  * * * * * * * * * * * * //

void Foam::viscosityModels::muI::readCoeffs()
{
    muICoeffs_.readEntry("mus", mus_);
    muICoeffs_.readEntry("deltaMu", deltaMu_);
    muICoeffs_.readEntry("I0", I0_);
    muICoeffs_.readEntry("d", d_);
    muICoeffs_.readEntry("etaMax", etaMax_);
    muICoeffs_.readEntry("pMin", pMin_);
    pName_ = muICoeffs_.get<word>("pName");
    viscosityProperties_.readEntry("rho", rho_);

    // Ranges: a bad value here would not fail, it would give wrong physics
    if
    (
        mus_.value() < 0 || deltaMu_.value() < 0 || I0_.value() <= 0
     || d_.value() <= 0 || rho_.value() <= 0 || etaMax_.value() <= 0
     || pMin_.value() <= 0
    )
    {
        FatalIOErrorInFunction(muICoeffs_)
            << "muI coefficients out of range: need mus >= 0, deltaMu >= 0,"
            << " I0 > 0, d > 0, rho > 0, etaMax > 0, pMin > 0; got"
            << " mus " << mus_.value() << ", deltaMu " << deltaMu_.value()
            << ", I0 " << I0_.value() << ", d " << d_.value()
            << ", rho " << rho_.value() << ", etaMax " << etaMax_.value()
            << ", pMin " << pMin_.value()
            << exit(FatalIOError);
    }
}


Foam::tmp<Foam::volScalarField>
Foam::viscosityModels::muI::calcNu() const
{
    const volScalarField* pPtr =
        U_.db().cfindObject<volScalarField>(pName_);

    if (!pPtr)
    {
        // At construction the solver has not made the pressure yet: the
        // grains start at the cap (exact for material at rest). Once it
        // runs, a missing field is a misspelt pName: never run a whole case
        // at the cap without a word.
        if (U_.time().timeIndex() > U_.time().startTimeIndex())
        {
            FatalIOErrorInFunction(muICoeffs_)
                << "the granular pressure field " << pName_
                << " (muICoeffs.pName) does not exist; fields: "
                << U_.db().sortedNames<volScalarField>()
                << exit(FatalIOError);
        }
        return tmp<volScalarField>::New
        (
            IOobject
            (
                "nuMuI",
                U_.time().timeName(),
                U_.db(),
                IOobject::NO_READ,
                IOobject::NO_WRITE,
                false
            ),
            U_.mesh(),
            etaMax_/rho_
        );
    }

    const volScalarField pPos(max(*pPtr, pMin_));
    const volScalarField sr(flooredStrainRate());
    const volScalarField I(inertialNumber(sr, pPos));

    return min(friction(I)*pPos/sr, etaMax_)/rho_;
}


Foam::tmp<Foam::volScalarField>
Foam::viscosityModels::muI::flooredStrainRate() const
{
    // |gammaDot| = sqrt(2)|symm(grad U)|, floored so that eta -> etaMax
    // (not NaN) where the material is at rest
    return max
    (
        strainRate(),
        dimensionedScalar("srMin", dimless/dimTime, VSMALL)
    );
}


Foam::tmp<Foam::volScalarField>
Foam::viscosityModels::muI::inertialNumber
(
    const volScalarField& sr,
    const volScalarField& pPos
) const
{
    return sr*d_/sqrt(pPos/rho_);
}


Foam::tmp<Foam::volScalarField>
Foam::viscosityModels::muI::dEtadp() const
{
    const volScalarField& p = U_.db().lookupObject<volScalarField>(pName_);
    const volScalarField pPos(max(p, pMin_));
    const volScalarField sr(flooredStrainRate());
    const volScalarField I(inertialNumber(sr, pPos));
    const volScalarField mu(friction(I));

    // I mu'(I) = d mu/d ln I by a central difference: the same for every
    // law a derived model defines through friction()
    const scalar eps = 1e-4;
    const volScalarField dMuDlnI
    (
        (friction((1 + eps)*I) - friction((1 - eps)*I))/(2*eps)
    );

    return
        pos(etaMax_ - mu*pPos/sr)*pos(p - pMin_)
       *(mu - 0.5*dMuDlnI)/sr;
}


Foam::tmp<Foam::volScalarField>
Foam::viscosityModels::muI::friction(const volScalarField& I) const
{
    // mu(I) = mus + deltaMu/(I0/I + 1), written without 1/I
    return mus_ + deltaMu_*I/(I0_ + I);
}


// * * * * * * * * * * * * * * * * Constructors  * * * * * * * * * * * * * * //

Foam::viscosityModels::muI::muI
(
    const word& name,
    const dictionary& viscosityProperties,
    const volVectorField& U,
    const surfaceScalarField& phi,
    const word& coeffsName
)
:
    viscosityModel(name, viscosityProperties, U, phi),
    muICoeffs_(viscosityProperties.optionalSubDict(coeffsName)),
    mus_("mus", dimless, Zero),
    deltaMu_("deltaMu", dimless, Zero),
    I0_("I0", dimless, Zero),
    d_("d", dimLength, Zero),
    rho_("rho", dimDensity, Zero),
    etaMax_("etaMax", dimDynamicViscosity, Zero),
    pMin_("pMin", dimPressure, Zero),
    pName_("p"),
    nu_
    (
        IOobject
        (
            name,
            U_.time().timeName(),
            U_.db(),
            IOobject::NO_READ,
            IOobject::AUTO_WRITE
        ),
        U_.mesh(),
        dimensionedScalar(dimViscosity, Zero)
    )
{
    readCoeffs();
    nu_ = calcNu();
}


Foam::viscosityModels::muI::muI
(
    const word& name,
    const dictionary& viscosityProperties,
    const volVectorField& U,
    const surfaceScalarField& phi
)
:
    muI(name, viscosityProperties, U, phi, typeName + "Coeffs")
{}


// * * * * * * * * * * * * * * Member Functions  * * * * * * * * * * * * * * //

bool Foam::viscosityModels::muI::read
(
    const dictionary& viscosityProperties
)
{
    viscosityModel::read(viscosityProperties);

    muICoeffs_ = viscosityProperties.optionalSubDict(type() + "Coeffs");

    readCoeffs();

    return true;
}


// ************************************************************************* //
