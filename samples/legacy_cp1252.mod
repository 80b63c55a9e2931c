MODULE Schweissen
! Alte Zelle: Schweißnaht am Träger, Maße in mm, Winkel in °.
! Datei aus einer älteren RobotWare-Version (Windows-1252, CRLF).
PERS tooldata tBrenner:=[TRUE,[[118.5,0,374.2],[0.906308,0,0.422618,0]],[3.2,[-20,0,150],[1,0,0,0],0,0,0]];
PERS wobjdata wTraeger:=[FALSE,TRUE,"",[[1200,-300,560],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];
CONST robtarget pNahtAnfang:=[[0,0,0],[0.258819,0,0.965926,0],[-1,-1,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
CONST robtarget pNahtEnde:=[[450,0,0],[0.258819,0,0.965926,0],[-1,-1,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
CONST jointtarget jService:=[[-90,0,0,0,45,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];

PROC Naht()
  ! Anfahren über dem Startpunkt (50 mm über der Naht)
  MoveJ Offs(pNahtAnfang,0,0,50),v1000,z10,tBrenner\WObj:=wTraeger;
  MoveL pNahtAnfang,v100,fine,tBrenner\WObj:=wTraeger;
  TPWrite "Naht läuft…";
  MoveL pNahtEnde,v10,fine,tBrenner\WObj:=wTraeger;
  MoveL Offs(pNahtEnde,0,0,50),v200,z10,tBrenner\WObj:=wTraeger;
  MoveAbsJ jService,v500,fine,tBrenner;
ENDPROC
ENDMODULE